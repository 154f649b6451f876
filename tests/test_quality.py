"""Quality levels and `auto` (`volren.quality`) and their derivation from bench results (`volren.bench.quality`)."""

from __future__ import annotations

import csv
import json
from dataclasses import replace

import numpy as np
import pytest

from volren import quality
from volren.bench.quality import derive, read_rows
from volren.cli.main import main
from volren.errors import VolrenError
from volren.model import RenderSettings
from volren.quality import LevelChoice, QualityTable, choose_renderer, settings_for
from volren.renderers.registry import registry

SCENES = [("a", "smooth"), ("b", "opaque")]


def rows_for(curve: str, label: str, errors: tuple[float, float], ms: float, kind: str = "uniform") -> list[dict]:
    return [{"dataset": d, "tf": tf, "kind": kind, "renderer": curve, "settings": label, "ms": str(ms),
             "rmse": str(e)} for (d, tf), e in zip(SCENES, errors, strict=True)]  # fmt: skip


def test_levels_are_the_fastest_configurations_within_each_bound_of_vtks_error():
    rows = rows_for("vtk-smart", "default", (0.01, 0.02), 300)
    rows += rows_for("slicer", "step 2, post", (0.05, 0.07), 40)  # 5x / 3.5x VTK's error
    rows += rows_for("slicer", "step 1, post", (0.03, 0.03), 60)  # 3x / 1.5x
    rows += rows_for("slicer", "step 0.5, post", (0.015, 0.02), 100)  # 1.5x / 1x
    rows += rows_for("slicer", "step 0.25, post", (0.008, 0.009), 180)  # 0.8x / 0.45x
    rows += rows_for("slicer", "step 0.25, pre 512", (0.002, 0.004), 200)  # 0.2x
    levels = derive(rows, "test").levels["uniform"]["slicer"]
    assert levels["draft"].label == "step 1, post"  # within 4x; step 2 is 5x on scene a
    assert levels["interactive"].label == "step 0.5, post"
    assert levels["default"].label == "step 0.25, post"
    assert levels["high"].label == levels["exact"].label == "step 0.25, pre 512"
    assert levels["default"].step == 0.25 and not levels["default"].preintegration
    assert levels["high"].preintegration and levels["high"].options["table_size"] == 512
    assert levels["draft"].ms == {"a/smooth": 60.0, "b/opaque": 60.0} and levels["draft"].worst_error_ratio == 3.0
    assert all(c.meets for c in levels.values())
    # VTK's own levels: its default configuration
    assert derive(rows, "test").levels["uniform"]["vtk"]["default"].options == {"mapper": "smart"}


def test_a_renderer_that_never_reaches_vtks_error_keeps_its_default_and_faster_drafts():
    rows = rows_for("vtk-smart", "default", (0.01, 0.01), 300)
    rows += rows_for("slicer", "step 1, post", (0.08, 0.09), 60)  # 9x
    rows += rows_for("slicer", "step 0.5, post", (0.05, 0.05), 100)  # 5x: the renderer's own default
    rows += rows_for("slicer", "step 0.25, pre 512", (0.02, 0.03), 900)  # 3x, its most accurate, slow
    levels = derive(rows, "test").levels["uniform"]["slicer"]
    assert levels["default"].label == "step 0.5, post" and not levels["default"].meets
    # draft's 4x bound is met only by the slow accurate setting: drafts are never slower than the default
    assert levels["draft"].label == levels["interactive"].label == "step 1, post"
    assert levels["exact"].label == "step 0.25, pre 512"


def test_read_rows_lets_a_later_file_win_and_refuses_other_files(tmp_path):
    first, second = tmp_path / "1.csv", tmp_path / "2.csv"
    for path, ms in ((first, 10), (second, 20)):
        rows = rows_for("slicer", "step 1, post", (0.1, 0.1), ms)
        with path.open("w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=list(rows[0]))
            writer.writeheader()
            writer.writerows(rows)
    assert {r["ms"] for r in read_rows([first, second])} == {"20"}
    (tmp_path / "x.csv").write_text("a,b\n1,2\n")
    with pytest.raises(VolrenError, match="x.csv: not a `volren bench run` runs.csv"):
        read_rows([tmp_path / "x.csv"])


def choice(ms: float, meets: bool = True, step: float = 0.5) -> LevelChoice:
    return LevelChoice("x", step, False, {}, {"a/smooth": ms}, 1.0, meets)


def table_of(**renderers) -> QualityTable:
    return QualityTable({"uniform": {name: {level: c for level in quality.LEVELS} for name, c in renderers.items()}}, "t")


def test_auto_takes_the_fastest_that_meets_the_level_and_can_draw_the_scene():
    table = table_of(slicer=choice(100), objectorder=choice(50), shearwarp=choice(10, meets=False))
    names = registry.names()
    assert choose_renderer("uniform", "default", 1, RenderSettings(), names, table)[0] == "objectorder"
    # a 2D TF: only the slicer of the three draws it
    assert choose_renderer("uniform", "default", 2, RenderSettings(), names, table)[0] == "slicer"
    # none meeting: the fastest measured
    table = table_of(slicer=choice(100, meets=False), shearwarp=choice(10, meets=False))
    assert choose_renderer("uniform", "draft", 1, RenderSettings(), names, table)[0] == "shearwarp"
    # nothing measured draws it: a registered renderer that can, never the reference
    name, why = choose_renderer("tet", "default", 1, RenderSettings(), names, table)
    assert name != "reference" and "no measured renderer" in why
    with pytest.raises(VolrenError, match="quality must be one of"):
        choose_renderer("uniform", "best", 1, RenderSettings(), names, table)


def test_settings_for_applies_the_level_and_keeps_the_callers_options():
    table = QualityTable({"uniform": {"slicer": {"draft": LevelChoice("s", 2.0, True, {"table_size": 64, "path": "march"},
                                                                      {}, 3.0)}}}, "t")  # fmt: skip
    got = settings_for("slicer", "uniform", "draft", RenderSettings(shade=True, options={"table_size": 128}), table)
    assert (got.step, got.preintegration, got.shade) == (2.0, True, True)
    assert got.options == {"table_size": 128, "path": "march"}
    assert settings_for("tetra", "uniform", "draft", RenderSettings(), table) == RenderSettings()


def test_the_committed_table_round_trips_and_covers_both_kinds():
    table = quality.table()
    assert QualityTable.from_json(json.loads(json.dumps(table.to_json())), "again") == table
    assert set(table.levels) == {f"{kind}{cls}" for kind in ("uniform", "tet") for cls in ("", "/smooth", "/sharp", "/band")}
    for kind, renderers in table.levels.items():
        for name, levels in renderers.items():
            assert list(levels) == list(quality.LEVELS), (kind, name)
            assert levels["exact"].worst_error_ratio <= levels["draft"].worst_error_ratio


@pytest.mark.usefixtures("opengl")
def test_the_cli_quality_flag_sets_the_measured_settings_and_flags_win(tmp_path, capsys, monkeypatch):
    table = QualityTable({"uniform": {"slicer": {level: LevelChoice("s", 2.0, False, {}, {"a/smooth": 1.0}, 1.0)
                                                 for level in quality.LEVELS}}}, "t")  # fmt: skip
    monkeypatch.setattr(quality, "table", lambda: table)
    from pathlib import Path

    volume = str(Path(__file__).parents[1] / "data_samples" / "marschner_lobb.vti")
    out = {}
    for name, extra in (("draft", ["--quality", "draft"]), ("step2", ["--step", "2"]), ("override", ["--quality", "draft", "--step", "1"]),
                        ("step1", ["--step", "1"])):  # fmt: skip
        out[name] = tmp_path / f"{name}.npy"
        assert main(["render", volume, "--renderer", "slicer", "--size", "24", "--save-array", str(out[name]), *extra]) == 0
    capsys.readouterr()
    assert np.array_equal(np.load(out["draft"]), np.load(out["step2"]))
    assert np.array_equal(np.load(out["override"]), np.load(out["step1"]))
    assert not np.array_equal(np.load(out["draft"]), np.load(out["step1"]))


def test_tf_sharpness_is_the_steepest_optical_depth_change_across_the_data_range():
    from volren.model import TransferFunction1D

    ramp = TransferFunction1D([[0, 1, 1, 1], [10, 1, 1, 1]], [[0, 0.0], [10, 0.5]])
    # -ln(1 - a) rises by ln 2 over the TF's whole span; over data spanning half of it, half that
    assert quality.tf_sharpness(ramp, (0.0, 10.0)) == pytest.approx(np.log(2.0))
    assert quality.tf_sharpness(ramp, (0.0, 5.0)) == pytest.approx(np.log(2.0) / 2)
    assert quality.tf_class(ramp, (0.0, 10.0)) == "smooth"
    # the same rise over a hundredth of the data's range is sharp
    assert quality.tf_sharpness(ramp, (0.0, 1000.0)) == pytest.approx(100 * np.log(2.0))
    assert quality.tf_class(ramp, (0.0, 1000.0)) == "sharp"
    step = TransferFunction1D([[0, 1, 1, 1], [10, 1, 1, 1]], [[0, 0.0], [5, 0.0], [5, 0.2], [10, 0.2]])
    assert quality.tf_sharpness(step, (0.0, 10.0)) == np.inf and quality.tf_class(step, (0.0, 10.0)) == "sharp"
    flat = TransferFunction1D([[0, 1, 1, 1], [10, 1, 1, 1]], [[0, 0.3], [10, 0.3]])
    assert quality.tf_sharpness(flat, (0.0, 10.0)) == 0.0
    assert quality.tf_sharpness(ramp, (3.0, 3.0)) == 0.0  # constant data: nothing to be sharp over
    assert quality.tf_class(object(), (0.0, 1.0)) is None  # not a 1D TF (a 2D one): no class
    assert quality.tf_visible_fraction(object(), (0.0, 1.0)) is None
    assert quality.scene_kind("uniform", ramp, (0.0, 1000.0)) == "uniform/sharp"
    assert quality.scene_kind("tet", object(), (0.0, 1.0)) == "tet"
    assert quality.base_kind("uniform/sharp") == "uniform"


def test_a_sharp_tf_visible_on_a_narrow_part_of_the_range_is_a_band_tf():
    from volren.model import TransferFunction1D

    grey = [[0, 1, 1, 1], [100, 1, 1, 1]]
    # a peak 4 wide (visible on (48, 52)) and a step up to a solid body (visible on (40, 100])
    peak = TransferFunction1D(grey, [[0, 0.0], [48, 0.0], [50, 0.9], [52, 0.0], [100, 0.0]])
    step = TransferFunction1D(grey, [[0, 0.0], [40, 0.0], [42, 0.9], [100, 0.9]])
    assert quality.tf_visible_fraction(peak, (0.0, 100.0)) == pytest.approx(0.04, abs=1e-3)
    assert quality.tf_visible_fraction(step, (0.0, 100.0)) == pytest.approx(0.6, abs=1e-3)
    assert quality.tf_sharpness(peak, (0.0, 100.0)) > quality.SHARP_TF
    assert quality.tf_class(peak, (0.0, 100.0)) == "band" and quality.tf_class(step, (0.0, 100.0)) == "sharp"
    # a gentle hump visible on a narrow part of a wide range stays smooth (band TFs are sharp ones)
    hump = TransferFunction1D(grey, [[0, 0.0], [45, 0.0], [50, 0.002], [55, 0.0], [100, 0.0]])
    assert quality.tf_class(hump, (0.0, 100.0)) == "smooth"
    assert quality.features_class(quality.SHARP_TF, quality.BAND_TF) == "sharp"
    assert quality.scene_kind("uniform", peak, (0.0, 100.0)) == "uniform/band"


def test_levels_are_also_chosen_per_tf_class_and_looked_up_with_a_fallback():
    rows = rows_for("vtk-smart", "default", (0.01, 0.01), 300)
    rows += rows_for("slicer", "step 1, post", (0.005, 0.03), 60)  # within on the smooth scene only
    rows += rows_for("slicer", "step 0.5, pre 512", (0.02, 0.005), 100)  # within on the opaque scene only
    rows += rows_for("slicer", "step 0.25, pre 512", (0.008, 0.004), 200)  # within on both
    classes = {("a", "smooth"): "smooth", ("b", "opaque"): "sharp"}
    table = derive(rows, "test", classes)
    assert table.choice("slicer", "uniform", "default").label == "step 0.25, pre 512"
    assert table.choice("slicer", "uniform/smooth", "default").label == "step 1, post"
    assert table.choice("slicer", "uniform/sharp", "default").label == "step 0.5, pre 512"
    assert table.choice("slicer", "uniform/smooth", "default").ms == {"a/smooth": 60.0}
    # a class the table lacks falls back to the kind's own levels
    lean = QualityTable({"uniform": table.levels["uniform"]}, "t")
    assert lean.choice("slicer", "uniform/smooth", "default").label == "step 0.25, pre 512"
    assert sorted(lean.measured("uniform/sharp")) == ["slicer", "vtk"]
    # settings are at the level they measure as for the TF's class first (step 1 is the sharp class's draft) ...
    smooth_default = table.choice("slicer", "uniform/smooth", "default").apply(RenderSettings())
    assert quality.level_of("slicer", "uniform/sharp", smooth_default, table) == "draft"
    # ... else at the other class's: a TF edited into the other class keeps its level
    sharp_high = table.choice("slicer", "uniform/sharp", "high").apply(RenderSettings())
    assert quality.level_of("slicer", "uniform/smooth", sharp_high, table) == "high"
    assert quality.level_of("slicer", "uniform/sharp", RenderSettings(step=0.3), table) is None
    # without classes only the kind's levels
    assert set(derive(rows, "test").levels) == {"uniform"}


def test_auto_chooses_by_the_tfs_class(monkeypatch):
    from volren.model import TransferFunction1D

    uniform = {name: {level: choice(ms) for level in quality.LEVELS} for name, ms in (("slicer", 100), ("objectorder", 50))}
    sharp = {name: {level: choice(ms) for level in quality.LEVELS} for name, ms in (("slicer", 30), ("objectorder", 80))}
    table = QualityTable({"uniform": uniform, "uniform/sharp": sharp}, "t")
    monkeypatch.setattr(quality, "table", lambda: table)
    smooth_tf = TransferFunction1D([[0, 1, 1, 1], [10, 1, 1, 1]], [[0, 0.0], [10, 0.5]])
    sharp_tf = TransferFunction1D([[0, 1, 1, 1], [10, 1, 1, 1]], [[0, 0.0], [5, 0.0], [5.01, 1.0], [10, 1.0]])
    for tf, wanted in ((smooth_tf, "objectorder"), (sharp_tf, "slicer")):
        kind = quality.scene_kind("uniform", tf, (0.0, 10.0))
        name, _settings, why = quality.resolve(kind, 1, "auto", None, RenderSettings())
        assert name == wanted and why == f"the fastest measured at quality default for a {kind[8:]} TF that draws this scene"


def test_bench_quality_classes_the_scenes_and_writes_the_auto_report(tmp_path, monkeypatch, capsys):
    monkeypatch.delenv("VOLREN_SHARED", raising=False)  # the bundled samples are classed without it
    rows = [{"dataset": "marschner_lobb", "tf": "sample", "kind": "uniform", "renderer": curve, "settings": label,
             "ms": str(ms), "rmse": str(rmse)}
            for curve, label, ms, rmse in (("vtk-smart", "default", 200.0, 0.01), ("slicer", "step 1, post", 40.0, 0.008),
                                           ("slicer", "step 0.5, post", 80.0, 0.004),
                                           ("vtk-fixed_point", "step 0.5", 100.0, 0.009))]  # fmt: skip
    runs = tmp_path / "runs.csv"
    with runs.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    out, md = tmp_path / "levels.json", tmp_path / "quality.md"
    assert main(["bench", "quality", str(runs), "--out", str(out), "--markdown", str(md)]) == 0
    printed = capsys.readouterr().out
    assert "TF class of marschner_lobb/sample: smooth" in printed
    table = QualityTable.from_json(json.loads(out.read_text()), "t")
    assert set(table.levels) == {"uniform", "uniform/smooth"}
    assert table.choice("slicer", "uniform/smooth", "default").label == "step 1, post"
    # the vtk renderer's default level is a faster VTK configuration within VTK's default's error; the
    # ratios are still against VTK's default itself (vtk-smart's default, 200 ms)
    assert table.choice("vtk", "uniform/smooth", "default").label == "vtk-fixed_point: step 0.5"
    text = md.read_text()
    # auto takes the slicer (the only one of ours measured): 200 / 40 ms, its worst RMSE 0.8x VTK's
    assert "| marschner_lobb/sample | smooth (12, 0.2) | slicer: step 1, post | 40 | 200 | 5.0x |" in text
    assert "| uniform | default | 5.0-5.0x (median 5.0x) over 1 scene, RMSE up to 0.8x |" in text


def test_auto_passes_over_a_renderer_that_cannot_draw_the_view():
    from volren.model import Camera

    table = table_of(shearwarp=choice(10), objectorder=choice(50))
    names = registry.names()
    bounds = (0.0, 10.0, 0.0, 8.0, 0.0, 6.0)
    outside = Camera.orbit(bounds, 30, 20)
    inside = Camera(position=(4.0, 3.0, 2.0), focal_point=(9.0, 7.0, 5.0), clipping_range=(0.01, 50.0))
    parallel_inside = Camera(position=(4.0, 3.0, 2.0), focal_point=(9.0, 7.0, 5.0), parallel=True,
                             clipping_range=(0.01, 50.0))  # fmt: skip

    def chosen(*cameras):
        return choose_renderer("uniform", "default", 1, RenderSettings(), names, table, cameras=cameras, bounds=bounds)[0]

    assert registry.capabilities("shearwarp").camera_reason("uniform", inside, bounds)
    assert chosen(outside) == "shearwarp" and chosen(parallel_inside) == "shearwarp"
    assert chosen(inside) == "objectorder"
    assert chosen(outside, inside) == "objectorder"  # a movie: every frame's view must be drawable
    # the app's own list of drawable renderers still meets the view test
    only = {"shearwarp", "objectorder"}
    assert choose_renderer("uniform", "default", 1, RenderSettings(), names, table, can_draw=only.__contains__,
                           cameras=(inside,), bounds=bounds)[0] == "objectorder"  # fmt: skip


def band_scene():
    """A 12^3 grid of values 0..99 and a band TF (a peak at 50): `auto` at `interactive` draws it
    with shearwarp from outside."""
    from volren.model import TransferFunction1D, UniformVolume

    values = np.fromfunction(lambda z, y, x: (x + 2 * y + 3 * z) % 100, (12, 12, 12)).astype(np.float32)
    volume = UniformVolume(values, spacing=(1.0, 1.0, 1.0), origin=(0.0, 0.0, 0.0))
    band = TransferFunction1D([[0, 1, 0.5, 0.2], [100, 1, 0.5, 0.2]], [[0, 0.0], [49, 0.0], [50, 1.0], [51, 0.0], [100, 0.0]], 0.2)
    return volume, band


def test_the_api_renders_from_inside_the_volume_with_auto_where_its_first_choice_cannot():
    import volren
    from volren.model import Camera

    volume, band = band_scene()
    kind = quality.scene_kind("uniform", band, volume.value_range)
    assert kind == "uniform/band" and quality.resolve(kind, 1, "auto", "interactive", RenderSettings())[0] == "shearwarp"
    inside = Camera(position=(5.0, 5.0, 5.0), focal_point=(11.0, 11.0, 11.0), clipping_range=(0.01, 50.0))
    with pytest.raises(VolrenError, match="inside"):
        volren.render(volume, band, renderer="shearwarp", camera=inside, size=(24, 24))
    image = volren.render(volume, band, camera=inside, size=(24, 24), quality="interactive")  # another draws it
    assert np.isfinite(image).all() and image[..., 3].max() > 0.05


def test_the_cli_renders_from_inside_the_volume_with_auto_and_names_the_renderer(tmp_path, capsys):
    from volren.io.volume_writer import save_volume
    from volren.model import Camera

    volume, band_tf = band_scene()
    volume_path = tmp_path / "v.vti"
    save_volume(volume, volume_path)
    band = band_tf.to_dict()
    inside = Camera(position=(5.0, 5.0, 5.0), focal_point=(11.0, 11.0, 11.0), clipping_range=(0.01, 50.0))
    scene = {"version": 1, "volume": {"path": str(volume_path)}, "transfer_function": band,
             "camera": inside.to_dict(), "size": [24, 24]}  # fmt: skip
    scene_path = tmp_path / "scene.json"
    scene_path.write_text(json.dumps(scene))
    assert main(["render", "--scene", str(scene_path), "--quality", "interactive",
                 "--save-array", str(tmp_path / "in.npy")]) == 0
    line = capsys.readouterr().out
    assert line.split(" ", 1)[0] != "shearwarp" and "(auto:" in line
    assert np.load(tmp_path / "in.npy")[..., 3].max() > 0.05
    scene["camera"] = {"azimuth": 30, "elevation": 20}  # from outside, the band TF's choice draws it
    scene_path.write_text(json.dumps(scene))
    assert main(["render", "--scene", str(scene_path), "--quality", "interactive",
                 "--save-array", str(tmp_path / "out.npy")]) == 0
    assert capsys.readouterr().out.startswith("shearwarp (auto:")


def test_clipping_planes_that_cut_a_mesh_pass_vtk_over():
    from volren.model import Camera
    from volren.renderers.base import clipping_planes_cut

    bounds = (0.0, 10.0, 0.0, 8.0, 0.0, 6.0)
    whole = Camera.orbit(bounds, 30, 20)
    near, far = whole.clipping_range
    depth = float(np.linalg.norm(np.asarray(whole.position) - np.asarray(whole.focal_point)))
    cut_near = replace(whole, clipping_range=(depth, far))  # through the box's centre
    cut_far = replace(whole, clipping_range=(near, depth))
    assert not clipping_planes_cut(whole, bounds)
    assert clipping_planes_cut(cut_near, bounds) and clipping_planes_cut(cut_far, bounds)
    vtk = registry.capabilities("vtk")
    assert vtk.camera_reason("tet", whole, bounds) is None
    assert "near or far plane cuts" in vtk.camera_reason("tet", cut_near, bounds)
    assert vtk.camera_reason("uniform", cut_near, bounds) is None  # the grid mappers clip
    tets = QualityTable({"tet": {"vtk": {level: choice(10) for level in quality.LEVELS},
                                 "tetra": {level: choice(50) for level in quality.LEVELS}}}, "t")  # fmt: skip
    names = registry.names()
    assert choose_renderer("tet", "default", 1, RenderSettings(), names, tets, cameras=(whole,), bounds=bounds)[0] == "vtk"
    assert choose_renderer("tet", "default", 1, RenderSettings(), names, tets, cameras=(cut_near,), bounds=bounds)[0] == "tetra"


def test_a_movie_from_inside_the_volume_refuses_up_front_or_goes_to_a_renderer_that_draws_it(tmp_path):
    from volren.model import Camera
    from volren.model.animation import Animation
    from volren.model.scene import Scene
    from volren.movie import render_movie

    volume, band = band_scene()
    inside = Camera(position=(5.5, 5.5, 5.0), focal_point=(5.5, 5.5, 11.0), clipping_range=(0.01, 50.0))
    animation = Animation(frames=3, fps=3)
    scene = Scene("v.vti", band, camera=inside, renderer="shearwarp", size=(16, 16), volume=volume)
    path = tmp_path / "m.gif"
    with pytest.raises(VolrenError, match=r"movie frame 1 of 3: renderer shearwarp cannot draw .* inside") as info:
        render_movie(scene, animation, path)
    assert "\n" not in str(info.value) and not path.exists()
    render_movie(replace(scene, renderer="auto"), animation, path)  # auto passes shearwarp over
    assert path.stat().st_size > 0


def test_default_and_above_never_interpolate_pixels_even_when_faster_and_within_the_bound():
    rows = rows_for("vtk-smart", "default", (0.01, 0.01), 300)
    rows += rows_for("raycast", "step 0.25, refine 8/0.02", (0.005, 0.005), 20)  # fast, accurate, interpolating
    rows += rows_for("raycast", "step 0.5 (default)", (0.008, 0.009), 100)
    rows += rows_for("raycast", "step 0.25, pre-integrated", (0.002, 0.002), 200)
    levels = derive(rows, "test").levels["uniform"]["raycast"]
    assert levels["draft"].label == levels["interactive"].label == "step 0.25, refine 8/0.02"
    assert levels["default"].label == "step 0.5 (default)"
    assert levels["high"].label == levels["exact"].label == "step 0.25, pre-integrated"
    assert all("image_stride" not in levels[level].options for level in ("default", "high", "exact"))


def test_default_keeps_no_more_pixels_off_than_vtks_default_where_counted():
    rows = [dict(r, off="3") for r in rows_for("vtk-smart", "default", (0.01, 0.01), 300)]
    # within VTK's RMSE on both scenes, but 40 pixels off by more than 0.1 on one (a dropped vessel)
    rows += [dict(r, off=o) for r, o in zip(rows_for("slicer", "step 0.5, post", (0.008, 0.009), 50), ("0", "40"))]
    rows += [dict(r, off="2") for r in rows_for("slicer", "step 0.25, post", (0.009, 0.009), 90)]
    levels = derive(rows, "test").levels["uniform"]["slicer"]
    assert levels["draft"].label == "step 0.5, post"  # previews may drop what VTK keeps
    assert levels["default"].label == "step 0.25, post"
    # where no configuration keeps the count, the level says it does not meet its bound
    rows = [r for r in rows if r["settings"] != "step 0.25, post"]
    assert not derive(rows, "test").levels["uniform"]["slicer"]["default"].meets


def test_the_committed_table_samples_every_pixel_at_default_and_above():
    for kind, renderers in quality.table().levels.items():
        for name, levels in renderers.items():
            for level in ("default", "high", "exact"):
                assert levels[level].options.get("image_stride", 1) == 1, (kind, name, level)


def test_a_later_run_of_other_scenes_binds_every_level_and_drops_what_it_did_not_measure():
    rows = rows_for("vtk-smart", "default", (0.01, 0.01), 300)
    rows += rows_for("slicer", "step 0.5, post", (0.009, 0.009), 50)
    rows += rows_for("slicer", "step 0.25, post", (0.005, 0.005), 90)
    # a later run at 128x128 (scenes of their own) where step 0.5 is 3x VTK's error, and a new
    # configuration measured only there
    small = [dict(r, size="128") for r in rows_for("vtk-smart", "default", (0.02, 0.02), 30)]
    small += [dict(r, size="128") for r in rows_for("slicer", "step 0.5, post", (0.06, 0.06), 5)]
    small += [dict(r, size="128") for r in rows_for("slicer", "step 0.25, post", (0.01, 0.01), 9)]
    small += [dict(r, size="128") for r in rows_for("slicer", "step 1, post", (0.001, 0.001), 1)]
    levels = derive(rows + small, "test").levels["uniform"]["slicer"]
    assert levels["default"].label == "step 0.25, post"
    assert set(levels["default"].ms) == {"a/smooth", "b/opaque", "a/smooth@128", "b/opaque@128"}
    assert all(c.label != "step 1, post" for c in levels.values())  # measured on the small scenes only


def test_default_is_chosen_with_a_margin_below_vtks_error():
    rows = rows_for("vtk-smart", "default", (0.01, 0.01), 300)
    rows += rows_for("slicer", "step 0.5, post", (0.0095, 0.0095), 50)  # within VTK's error, not its margin
    rows += rows_for("slicer", "step 0.25, post", (0.008, 0.008), 90)
    levels = derive(rows, "test").levels["uniform"]["slicer"]
    assert levels["default"].label == "step 0.25, post" and levels["default"].meets
    assert levels["interactive"].label == "step 0.5, post"
