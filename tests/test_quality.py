"""Quality levels and `auto` (`volren.quality`), each renderer's measured levels, and their derivation from
bench results (`benchmarks.quality_levels`)."""

from __future__ import annotations

import csv
import json
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from benchmarks.quality_levels import derive, read_rows
from benchmarks.quality_levels import main as quality_levels_main
from volren import quality
from volren.cli.main import main
from volren.errors import VolrenError
from volren.model import RenderSettings
from volren.model.scene_class import SceneClass
from volren.model.tf_class import TFClass
from volren.quality import Measurement, QualityTable, choose_renderer
from volren.renderers.base import QualityLevel
from volren.renderers.registry import registry

UNIFORM, TET = SceneClass("uniform"), SceneClass("tet")
SMOOTH, SHARP, BAND = (SceneClass("uniform", c) for c in (TFClass.SMOOTH, TFClass.SHARP, TFClass.BAND))

SCENES = [("a", "smooth"), ("b", "opaque")]


def rows_for(
    curve: str, label: str, errors: tuple[float, float], ms: float, kind: str = "uniform"
) -> list[dict]:
    return [{"dataset": d, "tf": tf, "kind": kind, "renderer": curve, "settings": label, "ms": str(ms),
             "rmse": str(e)} for (d, tf), e in zip(SCENES, errors, strict=True)]  # fmt: skip


def test_levels_are_the_fastest_configurations_within_each_bound_of_vtks_error():
    rows = rows_for("vtk-smart", "default", (0.01, 0.02), 300)
    rows += rows_for("slicer", "step 2, post", (0.05, 0.07), 40)  # 5x / 3.5x VTK's error
    rows += rows_for("slicer", "step 1, post", (0.03, 0.03), 60)  # 3x / 1.5x
    rows += rows_for("slicer", "step 0.5, post", (0.015, 0.02), 100)  # 1.5x / 1x
    rows += rows_for("slicer", "step 0.25, post", (0.008, 0.009), 180)  # 0.8x / 0.45x
    rows += rows_for("slicer", "step 0.25, pre 512", (0.002, 0.004), 200)  # 0.2x
    levels = derive(rows, "test").levels[UNIFORM]["slicer"]
    assert levels["draft"].level.label == "step 1, post"  # within 4x; step 2 is 5x on scene a
    assert levels["interactive"].level.label == "step 0.5, post"
    assert levels["default"].level.label == "step 0.25, post"
    assert levels["high"].level.label == levels["exact"].level.label == "step 0.25, pre 512"
    assert levels["default"].level.step == 0.25 and not levels["default"].level.preintegration
    assert levels["high"].level.preintegration and levels["high"].level.options["table_size"] == 512
    assert (
        levels["draft"].ms == {"a/smooth": 60.0, "b/opaque": 60.0}
        and levels["draft"].worst_error_ratio == 3.0
    )
    assert all(c.meets for c in levels.values())
    # VTK's own levels: its default configuration
    assert derive(rows, "test").levels[UNIFORM]["vtk"]["default"].level.options == {"mapper": "smart"}


def test_a_renderer_that_never_reaches_vtks_error_keeps_its_default_and_faster_drafts():
    rows = rows_for("vtk-smart", "default", (0.01, 0.01), 300)
    rows += rows_for("slicer", "step 1, post", (0.08, 0.09), 60)  # 9x
    rows += rows_for("slicer", "step 0.5, post", (0.05, 0.05), 100)  # 5x: the renderer's own default
    rows += rows_for("slicer", "step 0.25, pre 512", (0.02, 0.03), 900)  # 3x, its most accurate, slow
    levels = derive(rows, "test").levels[UNIFORM]["slicer"]
    assert levels["default"].level.label == "step 0.5, post" and not levels["default"].meets
    # draft's 4x bound is met only by the slow accurate setting: drafts are never slower than the default
    assert levels["draft"].level.label == levels["interactive"].level.label == "step 1, post"
    assert levels["exact"].level.label == "step 0.25, pre 512"


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


def choice(ms: float, meets: bool = True, step: float = 0.5) -> Measurement:
    return Measurement(QualityLevel("x", step, False, {}), {"a/smooth": ms}, {"a/smooth": 100.0}, 1.0, meets)


def table_of(**renderers) -> QualityTable:
    return QualityTable(
        {UNIFORM: {name: {level: c for level in quality.LEVELS} for name, c in renderers.items()}}, {}
    )


def test_auto_takes_the_fastest_that_meets_the_level_and_can_draw_the_scene():
    table = table_of(slicer=choice(100), objectorder=choice(50), shearwarp=choice(10, meets=False))
    names = registry.names()
    assert choose_renderer(UNIFORM, "default", 1, RenderSettings(), names, table)[0] == "objectorder"
    # a 2D TF: only the slicer of the three draws it
    assert choose_renderer(UNIFORM, "default", 2, RenderSettings(), names, table)[0] == "slicer"
    # none meeting: the fastest measured
    table = table_of(slicer=choice(100, meets=False), shearwarp=choice(10, meets=False))
    assert choose_renderer(UNIFORM, "draft", 1, RenderSettings(), names, table)[0] == "shearwarp"
    # nothing measured draws it: a registered renderer that can, never the reference
    name, why = choose_renderer(TET, "default", 1, RenderSettings(), names, table)
    assert name != "reference" and "no measured renderer" in why
    with pytest.raises(VolrenError, match="quality must be one of"):
        choose_renderer(UNIFORM, "best", 1, RenderSettings(), names, table)


def test_resolve_applies_the_level_and_keeps_the_callers_options(monkeypatch):
    level = QualityLevel("s", 2.0, True, {"table_size": 64, "path": "march"})
    table = QualityTable({UNIFORM: {"slicer": {"draft": Measurement(level, {}, {}, 3.0)}}}, {})
    monkeypatch.setattr(quality, "table", lambda: table)
    caller = RenderSettings(shade=True, options={"table_size": 128})
    name, got, why = quality.resolve(UNIFORM, 1, "slicer", "draft", caller)
    assert (name, got.step, got.preintegration, got.shade, why) == ("slicer", 2.0, True, True, None)
    assert got.options == {"table_size": 128, "path": "march"}
    assert quality.resolve(UNIFORM, 1, "tetra", "draft", RenderSettings())[1] == RenderSettings()
    # the app's chooser: exactly the level's settings, options replaced
    assert quality.at_level("slicer", SMOOTH, "draft", caller, table).options == {
        "table_size": 64,
        "path": "march",
    }


def test_the_committed_table_round_trips_and_covers_both_kinds():
    table = quality.table()
    again = QualityTable.merged(QualityTable.from_renderer_json(name, json.loads(json.dumps(table.renderer_json(name))),
                                                                "again") for name in table.sources)  # fmt: skip
    assert again == table
    assert set(table.levels) == {
        SceneClass(kind, cls) for kind in ("uniform", "tet") for cls in (None, *TFClass)
    }
    for kind, renderers in table.levels.items():
        for name, levels in renderers.items():
            assert list(levels) == list(quality.LEVELS), (kind, name)
            assert levels["exact"].worst_error_ratio <= levels["draft"].worst_error_ratio


@pytest.mark.usefixtures("opengl")
def test_the_cli_quality_flag_sets_the_measured_settings_and_flags_win(tmp_path, capsys, monkeypatch):
    level = QualityLevel("s", 2.0, False, {})
    table = QualityTable({UNIFORM: {"slicer": {name: Measurement(level, {"a/smooth": 1.0}, {"a/smooth": 1.0}, 1.0)
                                               for name in quality.LEVELS}}}, {})  # fmt: skip
    monkeypatch.setattr(quality, "table", lambda: table)
    from pathlib import Path

    volume = str(Path(__file__).parents[1] / "data_samples" / "marschner_lobb.vti")
    out = {}
    for name, extra in (("draft", ["--quality", "draft"]), ("step2", ["--step", "2"]), ("override", ["--quality", "draft", "--step", "1"]),
                        ("step1", ["--step", "1"])):  # fmt: skip
        out[name] = tmp_path / f"{name}.npy"
        assert (
            main(
                [
                    "render",
                    volume,
                    "--renderer",
                    "slicer",
                    "--size",
                    "24",
                    "--save-array",
                    str(out[name]),
                    *extra,
                ]
            )
            == 0
        )
    capsys.readouterr()
    assert np.array_equal(np.load(out["draft"]), np.load(out["step2"]))
    assert np.array_equal(np.load(out["override"]), np.load(out["step1"]))
    assert not np.array_equal(np.load(out["draft"]), np.load(out["step1"]))


def test_levels_are_also_chosen_per_tf_class_and_looked_up_with_a_fallback():
    rows = rows_for("vtk-smart", "default", (0.01, 0.01), 300)
    rows += rows_for("slicer", "step 1, post", (0.005, 0.03), 60)  # within on the smooth scene only
    rows += rows_for("slicer", "step 0.5, pre 512", (0.02, 0.005), 100)  # within on the opaque scene only
    rows += rows_for("slicer", "step 0.25, pre 512", (0.008, 0.004), 200)  # within on both
    classes = {("a", "smooth"): TFClass.SMOOTH, ("b", "opaque"): TFClass.SHARP}
    table = derive(rows, "test", classes)
    assert table.measurement("slicer", UNIFORM, "default").level.label == "step 0.25, pre 512"
    assert table.measurement("slicer", SMOOTH, "default").level.label == "step 1, post"
    assert table.measurement("slicer", SHARP, "default").level.label == "step 0.5, pre 512"
    assert table.measurement("slicer", SMOOTH, "default").ms == {"a/smooth": 60.0}
    # a class the table lacks falls back to the kind's own levels
    lean = QualityTable({UNIFORM: table.levels[UNIFORM]}, {})
    assert lean.measurement("slicer", SMOOTH, "default").level.label == "step 0.25, pre 512"
    assert sorted(lean.measured(SHARP)) == ["slicer", "vtk"]
    # settings are at the level they measure as for the TF's class first (step 1 is the sharp class's draft) ...
    smooth_default = table.measurement("slicer", SMOOTH, "default").level.apply(RenderSettings())
    assert quality.level_of("slicer", SHARP, smooth_default, table) == "draft"
    # ... else at the other class's: a TF edited into the other class keeps its level
    sharp_high = table.measurement("slicer", SHARP, "high").level.apply(RenderSettings())
    assert quality.level_of("slicer", SMOOTH, sharp_high, table) == "high"
    assert quality.level_of("slicer", SHARP, RenderSettings(step=0.3), table) is None
    # without classes only the kind's levels
    assert set(derive(rows, "test").levels) == {UNIFORM}


def test_auto_chooses_by_the_tfs_class(monkeypatch):
    from volren.model import TransferFunction1D

    uniform = {
        name: {level: choice(ms) for level in quality.LEVELS}
        for name, ms in (("slicer", 100), ("objectorder", 50))
    }
    sharp = {
        name: {level: choice(ms) for level in quality.LEVELS}
        for name, ms in (("slicer", 30), ("objectorder", 80))
    }
    table = QualityTable({UNIFORM: uniform, SHARP: sharp}, {})
    monkeypatch.setattr(quality, "table", lambda: table)
    smooth_tf = TransferFunction1D([[0, 1, 1, 1], [10, 1, 1, 1]], [[0, 0.0], [10, 0.5]])
    sharp_tf = TransferFunction1D([[0, 1, 1, 1], [10, 1, 1, 1]], [[0, 0.0], [5, 0.0], [5.01, 1.0], [10, 1.0]])
    for tf, wanted in ((smooth_tf, "objectorder"), (sharp_tf, "slicer")):
        kind = SceneClass.of(SimpleNamespace(kind="uniform", value_range=(0.0, 10.0)), tf)
        name, _settings, why = quality.resolve(kind, 1, "auto", None, RenderSettings())
        assert (
            name == wanted
            and why
            == f"the fastest measured at quality default for a {kind.tf.value} TF that draws this scene"
        )


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
    out, md = tmp_path / "levels", tmp_path / "quality.md"
    assert quality_levels_main([str(runs), "--out", str(out), "--markdown", str(md)]) == 0
    printed = capsys.readouterr().out
    assert "TF class of marschner_lobb/sample: smooth" in printed
    assert sorted(p.name for p in out.iterdir()) == ["slicer", "vtk"]  # one file per renderer
    table = QualityTable.merged(
        quality.read_levels(name, out / name / quality.LEVELS_FILE) for name in ("slicer", "vtk")
    )
    assert set(table.levels) == {UNIFORM, SMOOTH}
    assert table.measurement("slicer", SMOOTH, "default").level.label == "step 1, post"
    assert table.measurement("slicer", SMOOTH, "default").peer_ms == {"marschner_lobb/sample": 200.0}
    # the vtk renderer's default level is a faster VTK configuration within VTK's default's error; the
    # ratios are still against VTK's default itself (vtk-smart's default, 200 ms)
    assert table.measurement("vtk", SMOOTH, "default").level.label == "vtk-fixed_point: step 0.5"
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
        return choose_renderer(
            UNIFORM, "default", 1, RenderSettings(), names, table, cameras=cameras, bounds=bounds
        )[0]

    assert registry.capabilities("shearwarp").camera_reason("uniform", inside, bounds)
    assert chosen(outside) == "shearwarp" and chosen(parallel_inside) == "shearwarp"
    assert chosen(inside) == "objectorder"
    assert chosen(outside, inside) == "objectorder"  # a movie: every frame's view must be drawable
    # the app's own list of drawable renderers still meets the view test
    only = {"shearwarp", "objectorder"}
    assert choose_renderer(UNIFORM, "default", 1, RenderSettings(), names, table, can_draw=only.__contains__,
                           cameras=(inside,), bounds=bounds)[0] == "objectorder"  # fmt: skip


def band_scene():
    """A 12^3 grid of values 0..99 and a band TF (a peak at 50): `auto` at `interactive` draws it
    with shearwarp from outside."""
    from volren.model import TransferFunction1D, UniformVolume

    values = np.fromfunction(lambda z, y, x: (x + 2 * y + 3 * z) % 100, (12, 12, 12)).astype(np.float32)
    volume = UniformVolume(values, spacing=(1.0, 1.0, 1.0), origin=(0.0, 0.0, 0.0))
    band = TransferFunction1D(
        [[0, 1, 0.5, 0.2], [100, 1, 0.5, 0.2]], [[0, 0.0], [49, 0.0], [50, 1.0], [51, 0.0], [100, 0.0]], 0.2
    )
    return volume, band


def test_the_api_renders_from_inside_the_volume_with_auto_where_its_first_choice_cannot():
    import volren
    from volren.model import Camera

    volume, band = band_scene()
    kind = SceneClass.of(volume, band)
    assert (
        kind == BAND and quality.resolve(kind, 1, "auto", "interactive", RenderSettings())[0] == "shearwarp"
    )
    inside = Camera(position=(5.0, 5.0, 5.0), focal_point=(11.0, 11.0, 11.0), clipping_range=(0.01, 50.0))
    with pytest.raises(VolrenError, match="inside"):
        volren.render(volume, band, renderer="shearwarp", camera=inside, size=(24, 24))
    image = volren.render(
        volume, band, camera=inside, size=(24, 24), quality="interactive"
    )  # another draws it
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
    assert (
        main(
            [
                "render",
                "--scene",
                str(scene_path),
                "--quality",
                "interactive",
                "--save-array",
                str(tmp_path / "in.npy"),
            ]
        )
        == 0
    )
    line = capsys.readouterr().out
    assert line.split(" ", 1)[0] != "shearwarp" and "(auto:" in line
    assert np.load(tmp_path / "in.npy")[..., 3].max() > 0.05
    scene["camera"] = {"azimuth": 30, "elevation": 20}  # from outside, the band TF's choice draws it
    scene_path.write_text(json.dumps(scene))
    assert (
        main(
            [
                "render",
                "--scene",
                str(scene_path),
                "--quality",
                "interactive",
                "--save-array",
                str(tmp_path / "out.npy"),
            ]
        )
        == 0
    )
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
    tets = QualityTable({TET: {"vtk": {level: choice(10) for level in quality.LEVELS},
                               "tetra": {level: choice(50) for level in quality.LEVELS}}}, {})  # fmt: skip
    names = registry.names()
    assert (
        choose_renderer(TET, "default", 1, RenderSettings(), names, tets, cameras=(whole,), bounds=bounds)[0]
        == "vtk"
    )
    assert (
        choose_renderer(TET, "default", 1, RenderSettings(), names, tets, cameras=(cut_near,), bounds=bounds)[
            0
        ]
        == "tetra"
    )


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
    with pytest.raises(
        VolrenError, match=r"movie frame 1 of 3: renderer shearwarp cannot draw .* inside"
    ) as info:
        render_movie(scene, animation, path)
    assert "\n" not in str(info.value) and not path.exists()
    render_movie(replace(scene, renderer="auto"), animation, path)  # auto passes shearwarp over
    assert path.stat().st_size > 0


def test_default_and_above_never_interpolate_pixels_even_when_faster_and_within_the_bound():
    rows = rows_for("vtk-smart", "default", (0.01, 0.01), 300)
    rows += rows_for(
        "raycast", "step 0.25, refine 8/0.02", (0.005, 0.005), 20
    )  # fast, accurate, interpolating
    rows += rows_for("raycast", "step 0.5 (default)", (0.008, 0.009), 100)
    rows += rows_for("raycast", "step 0.25, pre-integrated", (0.002, 0.002), 200)
    levels = derive(rows, "test").levels[UNIFORM]["raycast"]
    assert levels["draft"].level.label == levels["interactive"].level.label == "step 0.25, refine 8/0.02"
    assert levels["default"].level.label == "step 0.5 (default)"
    assert levels["high"].level.label == levels["exact"].level.label == "step 0.25, pre-integrated"
    assert all("image_stride" not in levels[level].level.options for level in ("default", "high", "exact"))


def test_default_keeps_no_more_pixels_off_than_vtks_default_where_counted():
    rows = [dict(r, off="3") for r in rows_for("vtk-smart", "default", (0.01, 0.01), 300)]
    # within VTK's RMSE on both scenes, but 40 pixels off by more than 0.1 on one (a dropped vessel)
    rows += [
        dict(r, off=o) for r, o in zip(rows_for("slicer", "step 0.5, post", (0.008, 0.009), 50), ("0", "40"))
    ]
    rows += [dict(r, off="2") for r in rows_for("slicer", "step 0.25, post", (0.009, 0.009), 90)]
    levels = derive(rows, "test").levels[UNIFORM]["slicer"]
    assert levels["draft"].level.label == "step 0.5, post"  # previews may drop what VTK keeps
    assert levels["default"].level.label == "step 0.25, post"
    # where no configuration keeps the count, the level says it does not meet its bound
    rows = [r for r in rows if r["settings"] != "step 0.25, post"]
    assert not derive(rows, "test").levels[UNIFORM]["slicer"]["default"].meets


def test_the_committed_table_samples_every_pixel_at_default_and_above():
    for kind, renderers in quality.table().levels.items():
        for name, levels in renderers.items():
            for level in ("default", "high", "exact"):
                assert levels[level].level.options.get("image_stride", 1) == 1, (kind, name, level)


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
    levels = derive(rows + small, "test").levels[UNIFORM]["slicer"]
    assert levels["default"].level.label == "step 0.25, post"
    assert set(levels["default"].ms) == {"a/smooth", "b/opaque", "a/smooth@128", "b/opaque@128"}
    assert all(c.level.label != "step 1, post" for c in levels.values())  # measured on the small scenes only


def test_default_is_chosen_with_a_margin_below_vtks_error():
    rows = rows_for("vtk-smart", "default", (0.01, 0.01), 300)
    rows += rows_for("slicer", "step 0.5, post", (0.0095, 0.0095), 50)  # within VTK's error, not its margin
    rows += rows_for("slicer", "step 0.25, post", (0.008, 0.008), 90)
    levels = derive(rows, "test").levels[UNIFORM]["slicer"]
    assert levels["default"].level.label == "step 0.25, post" and levels["default"].meets
    assert levels["interactive"].level.label == "step 0.5, post"


def test_each_renderer_ships_its_levels_in_its_own_package_and_the_core_names_no_plugin():
    from pathlib import Path

    import volren_objectorder
    import volren_shearwarp

    core = Path(quality.__file__).parent
    for name, package in (("shearwarp", volren_shearwarp), ("objectorder", volren_objectorder)):
        path = registry.data_file(name, quality.LEVELS_FILE)  # found through its entry point
        assert path == Path(package.__file__).parent / quality.LEVELS_FILE
        assert name in quality.table().measured(UNIFORM)
    core_files = sorted(core.rglob(quality.LEVELS_FILE))
    assert {p.parent.name for p in core_files} == {"raycast", "slicer", "tetra", "vtk_mappers"}
    for path in core_files:
        text = path.read_text()
        assert "shearwarp" not in text and "objectorder" not in text, path
        assert quality.read_levels("x", path).levels  # a table, under whatever name it is read


def test_auto_ranks_by_time_ratios_which_order_the_committed_runs_as_their_frame_times():
    """Every scene of the committed levels was measured with VTK's default in the same run, so each
    scene's peer time is the same for every renderer, and ranking by time ratios orders the
    renderers as their summed frame times do: `auto`'s choices are the fastest measured."""
    table = quality.table()
    names = registry.names()
    checked = 0
    for scene, renderers in table.levels.items():
        peers: dict[str, float] = {}
        for per in renderers.values():
            for m in per.values():
                for s, ms in m.peer_ms.items():
                    assert peers.setdefault(s, ms) == ms, (scene, s)  # one run's peer per scene
        for level in quality.LEVELS:
            found = {
                n: table.measurement(n, scene, level)
                for n in table.measured(scene)
                if n not in quality.NOT_AUTO
            }
            common = set.intersection(*(set(m.ms) for m in found.values()))
            by_ms = sorted(found, key=lambda n: (not found[n].meets, sum(found[n].ms[s] for s in common)))
            assert quality.ranked(scene, level, names, table) == by_ms, (scene, level)
            fastest_meeting = by_ms[0]
            assert choose_renderer(scene, level, 1, RenderSettings(), names, table)[0] == fastest_meeting, (
                scene,
                level,
            )
            checked += 1
    assert checked == len(table.levels) * len(quality.LEVELS) > 0


def test_ratios_to_each_runs_peer_rank_runs_from_different_machines_fairly():
    """A renderer measured on a machine twice as slow (its peer twice as slow too) ranks by its
    ratio, not its frame times."""
    fast_machine = Measurement(QualityLevel("a", 0.5, False, {}), {"s": 100.0}, {"s": 200.0}, 1.0)
    slow_machine = Measurement(QualityLevel("b", 0.5, False, {}), {"s": 150.0}, {"s": 400.0}, 1.0)
    table = QualityTable({UNIFORM: {"slicer": {level: fast_machine for level in quality.LEVELS},
                                    "raycast": {level: slow_machine for level in quality.LEVELS}}}, {})  # fmt: skip
    assert slow_machine.time_ratio(["s"]) == 0.375 and fast_machine.time_ratio(["s"]) == 0.5
    assert quality.ranked(UNIFORM, "default", ["slicer", "raycast"], table) == ["raycast", "slicer"]
