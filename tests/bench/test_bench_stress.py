"""`volren bench stress`: the checks count exactly what they should, the generated cases are the
corners they claim to be, broken renderers and tables are caught (non-zero exit), and a small run
through the CLI writes a CSV and stress.md with zero NaN/Inf/out-of-range counts."""

from __future__ import annotations

import csv
import math
from typing import ClassVar

import numpy as np
import pytest

from volren.bench import stress, stress_cases
from volren.cli.main import main
from volren.errors import VolrenError
from volren.model.settings import RenderSettings
from volren.model.tet_mesh import build_mesh
from volren.model.tet_repair import repair_tets, signed_volumes
from volren.renderers.base import Capabilities, KindSupport
from volren.renderers.reference.renderer import ReferenceRenderer
from volren.renderers.registry import BUILTIN_ENTRY_POINTS, RendererRegistry, registry
from volren.testing.metrics import image_error

NAN_PIXELS = 7


class NanRenderer(ReferenceRenderer):
    """The reference's image with NaN in its first NAN_PIXELS pixels (a broken renderer)."""

    name: ClassVar[str] = "stress-nan"
    capabilities: ClassVar[Capabilities] = Capabilities({"uniform": KindSupport(preintegration=True)})

    def _render(self, camera, width, height, progress):
        image, counters = super()._render(camera, width, height, progress)
        image.reshape(-1, 4)[:NAN_PIXELS, 1] = np.nan
        return image, counters


class HalfRenderer(ReferenceRenderer):
    """The reference's image at half intensity, with shading: a known error against it."""

    name: ClassVar[str] = "stress-half"
    capabilities: ClassVar[Capabilities] = Capabilities({"uniform": KindSupport(shading=True)})

    def _render(self, camera, width, height, progress):
        image, counters = super()._render(camera, width, height, progress)
        return image * np.float32(0.5), counters


class PickyRenderer(ReferenceRenderer):
    name: ClassVar[str] = "stress-picky"
    capabilities: ClassVar[Capabilities] = Capabilities({"uniform": KindSupport()})

    def _render(self, camera, width, height, progress):
        raise VolrenError("stress-picky refuses this scene")


class CrashRenderer(ReferenceRenderer):
    name: ClassVar[str] = "stress-crash"
    capabilities: ClassVar[Capabilities] = Capabilities({"uniform": KindSupport()})

    def _render(self, camera, width, height, progress):
        raise ZeroDivisionError("boom")


FAKES = {cls.name: cls for cls in (NanRenderer, HalfRenderer, PickyRenderer, CrashRenderer)}


@pytest.fixture()
def private_registry() -> RendererRegistry:
    reg = RendererRegistry(entry_points=lambda: [], builtin_fallback=True)
    for name, cls in FAKES.items():
        reg.register(name, cls)
    return reg


# ------------------------------------------------------------------------------ checks
def test_check_rgba_counts_each_bad_pixel_once():
    pixels = np.array(
        [
            [0.2, 0.1, 0.0, 0.5],  # fine
            [np.nan, np.inf, 0.0, 0.5],  # NaN wins over Inf
            [0.0, -np.inf, 0.0, 0.5],  # Inf
            [-1e-7, 0.0, 0.0, 0.5],  # below 0
            [0.5, 0.5, 0.5, 1.0000001],  # alpha above 1
            [0.6, 0.0, 0.0, 0.5],  # colour above alpha
            [0.50005, 0.0, 0.0, 0.5],  # within eps
        ],
        dtype=np.float32,
    ).reshape(7, 1, 4)
    for rule, out_of_range, excess in (
        (stress_cases.PREMULTIPLIED, 3, 0.1),  # the largest break: colour 0.6 over alpha 0.5
        (stress_cases.UNIT, 2, 1.2e-7),  # alpha 1.0000001 over 1
        (stress_cases.BELOW_ALPHA, 1, 0.1),
    ):
        counts = stress.check_rgba(pixels, rule)
        assert (counts.values, counts.nan, counts.inf, counts.out_of_range) == (7, 1, 1, out_of_range)
        assert counts.excess == pytest.approx(excess, rel=0.01)
    assert stress.check_rgba(pixels[:1]) == stress.Counts(1, 0, 0, 0, 0.0)
    with pytest.raises(ValueError):
        stress.check_rgba(pixels, "bogus")


# ------------------------------------------------------------------------------- cases
def test_kuhn_box_is_a_conforming_positive_tetrahedralization():
    points, tets = stress_cases.kuhn_box(5)
    volumes = signed_volumes(points, tets)
    assert len(tets) == 6 * 5**3 and volumes.min() > 0 and math.isclose(volumes.sum(), 1.0)
    mesh = build_mesh(points, tets, np.zeros(len(points)))
    assert mesh.n_boundary == 6 * 5 * 5 * 2  # two triangles per boundary square: no cracks inside


def test_tet_cases_hold_the_defects_they_name():
    tets = stress_cases.tet_volumes()
    clean = tets["tet-box"]()
    flat = tets["tet-flat"]()
    assert repair_tets(flat.points, flat.tets).dropped_degenerate == len(flat.tets) - len(clean.tets) > 20
    inverted = tets["tet-inverted"]()
    assert (signed_volumes(inverted.points, inverted.tets) < 0).mean() > 0.3
    dup = tets["tet-duplicated"]()
    assert len(dup.points) == 2 * len(clean.points) and (dup.tets >= len(clean.points)).any()
    sliver = tets["tet-sliver"]()
    thin = np.abs(signed_volumes(sliver.points, sliver.tets))
    assert thin.min() < 1e-9 * thin.max()  # the 1e-13 layer; the 1e-7 one is slivers
    assert np.isnan(tets["tet-nonfinite"]().values).sum() == 12


def test_uniform_cases_cover_the_dtypes_and_ranges():
    vols = {name: build() for name, build in stress_cases.uniform_volumes().items()}
    assert {str(v.values.dtype) for v in vols.values()} == {"uint8", "int16", "float32", "float64"}
    assert vols["constant"].value_range[0] == vols["constant"].value_range[1]
    assert vols["f64-1e300"].value_range == pytest.approx((-1e300, 1e300))
    assert vols["f32-1e-30"].value_range[1] == pytest.approx(1e-30, rel=1e-6)
    assert vols["i16-full"].value_range == (-32768.0, 32767.0)
    assert vols["nonfinite"].nonfinite_count > 0
    assert vols["spacing-1e-6"].spacing == (1e-6,) * 3 and vols["spacing-1e6"].spacing == (1e6,) * 3


def test_spike_is_narrower_than_a_voxel_value_change():
    volume = stress_cases.uniform_volumes()["f32-blob"]()
    tf = stress_cases.make_tf("spike", volume, 0)
    xs = tf.opacity_points[:, 0]
    typical_change = np.median(np.abs(np.diff(volume.values.astype(np.float64), axis=2)))
    assert xs[3] - xs[1] < 1e-2 * typical_change


# ------------------------------------------------------------------------------ images
def test_fake_renderers_are_flagged_and_errors_measured(private_registry):
    names = list(FAKES)
    work = stress.plan(False, private_registry, names, ["f32-blob/one"], tables=False)
    labels = [(j.config.renderer, j.config.label) for j in work.images]
    assert labels == [
        ("reference", "post flat"),
        ("reference", "post shade"),  # stress-half shades, so the oracle is rendered shaded too
        *[
            (n, lab)
            for n in sorted(FAKES)
            for lab in {
                "stress-crash": ["post flat"],
                "stress-half": ["post flat", "post shade"],
                "stress-nan": ["post flat", "pre flat"],
                "stress-picky": ["post flat"],
            }[n]
        ],
    ]
    rows = stress.run(work, private_registry, size=24)
    by = {(r.renderer, r.settings): r for r in rows}
    assert all(by[("reference", s)].status == "ok" for s in ("post flat", "post shade"))
    for label in ("post flat", "pre flat"):
        row = by[("stress-nan", label)]
        assert (row.status, row.nan, row.inf, row.out_of_range, row.values) == (
            "bad",
            NAN_PIXELS,
            0,
            0,
            24 * 24,
        )
    assert by[("stress-picky", "post flat")].status == "rejected"
    assert "refuses this scene" in by[("stress-picky", "post flat")].message
    crash = by[("stress-crash", "post flat")]
    assert crash.status == "failed" and crash.message.startswith("ZeroDivisionError: boom")

    case = next(c for c in stress_cases.scene_cases() if c.name == "f32-blob/one")
    for shade in (False, True):
        with ReferenceRenderer() as ref:
            ref.set_volume(case.volume)
            ref.set_transfer_function(case.tf)
            ref.set_settings(RenderSettings(shade=shade))
            truth = ref.render(case.camera, 24, 24)
        expected = image_error(truth * np.float32(0.5), truth)
        row = by[("stress-half", "post shade" if shade else "post flat")]
        assert row.status == "ok" and expected.rmse > 0.01
        assert row.rmse == pytest.approx(expected.rmse) and row.max_abs == pytest.approx(expected.max_abs)
    assert {(r.renderer, r.settings) for r in stress.problems(rows)} == {
        ("stress-nan", "post flat"),
        ("stress-nan", "pre flat"),
        ("stress-crash", "post flat"),
    }
    summary = {s.renderer: s for s in stress.summarize(rows)}
    assert summary["stress-nan"].nan == 2 * NAN_PIXELS and summary["stress-crash"].counts["failed"] == 1


def test_unknown_case_pattern_is_a_clear_error(private_registry):
    with pytest.raises(VolrenError, match="no stress case"):
        stress.plan(True, private_registry, [], ["no-such-case"])


# ------------------------------------------------------------------------------ tables
def test_table_checks_catch_nan_crash_and_rejection():
    def nan_table() -> stress_cases.TableOutput:
        table = np.full((3, 3, 4), 0.25)
        table[0, 0, 3] = np.nan
        return stress_cases.TableOutput(((table, stress_cases.PREMULTIPLIED),))

    def refuse() -> stress_cases.TableOutput:
        raise VolrenError("too big")

    def crash() -> stress_cases.TableOutput:
        raise FloatingPointError("overflow")

    case = stress_cases.TableCase("fake", "tf", (("a", nan_table), ("b", refuse), ("c", crash)))
    row = stress.run_table(case, stress.COLOR_EPS)
    assert (row.status, row.values, row.nan) == ("failed", 9, 1)
    assert "a: 1 NaN" in row.message and "c: FloatingPointError: overflow" in row.message
    assert "1 rejected, e.g. b: too big" in row.message
    only_refused = stress.run_table(stress_cases.TableCase("fake", "tf", (("b", refuse),)), stress.COLOR_EPS)
    assert only_refused.status == "rejected" and not only_refused.problem


def test_real_exact_table_passes_and_matches_the_continuous_integral():
    case = next(c for c in stress_cases.table_cases(quick=True) if c.function == "preintegrate 2D")
    row = stress.run_table(case, stress.COLOR_EPS)
    assert row.status == "ok" and row.values > 0 and row.nan == row.inf == row.out_of_range == 0
    assert 0 <= row.max_abs < 1e-3


# --------------------------------------------------------------------------------- CLI
def test_cli_writes_csv_and_markdown_with_zero_counts(tmp_path, capsys, renders_with_vtk):
    args = ["bench", "stress", "--quick", "--suites", "images", "--cases", "f32-blob/zero,constant/*"]
    assert main([*args, "--renderers", "vtk", "--size", "24", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "| renderer | runs |" in out and "0 with NaN, Inf, out-of-range values or a crash" in out
    with (tmp_path / "stress.csv").open() as f:
        reader = csv.DictReader(f)
        rows = list(reader)
    assert tuple(reader.fieldnames) == stress.COLUMNS
    assert {r["case"] for r in rows} == {"f32-blob/zero", "constant/spike"}
    assert {r["renderer"] for r in rows} == {"reference", "vtk"} and len(rows) == 8
    assert all(r["nan"] == r["inf"] == r["out_of_range"] == "0" and r["status"] == "ok" for r in rows)
    zero = [r for r in rows if r["case"] == "f32-blob/zero" and r["renderer"] == "vtk"]
    assert all(float(r["rmse"]) == 0.0 for r in zero)  # opacity 0 everywhere: black, exactly
    text = (tmp_path / "stress.md").read_text()
    assert "Problems (0):" in text and text.count("| f32-blob/zero |") >= 4


@pytest.fixture()
def nan_plugin():
    registry.register("stress-nan", NanRenderer)
    try:
        yield "stress-nan"
    finally:
        registry.unregister("stress-nan")


def test_cli_exits_non_zero_on_a_nan_renderer(nan_plugin, tmp_path, capsys):
    args = ["bench", "stress", "--suites", "images", "--cases", "f32-blob/zero", "--renderers", nan_plugin]
    assert main([*args, "--size", "16", "--out", str(tmp_path)]) == 1
    captured = capsys.readouterr()
    assert f"problem: f32-blob/zero stress-nan (post flat): bad: {NAN_PIXELS} NaN, 0 Inf" in captured.err
    with (tmp_path / "stress.csv").open() as f:
        bad = [r for r in csv.DictReader(f) if r["renderer"] == nan_plugin]
    assert [int(r["nan"]) for r in bad] == [NAN_PIXELS, NAN_PIXELS]
    assert set(BUILTIN_ENTRY_POINTS) <= set(registry.names())


def test_cli_rejects_bad_arguments(capsys):
    assert main(["bench", "stress", "--suites", "pictures"]) == 1
    assert main(["bench", "stress", "--size", "2"]) == 1
    assert main(["bench", "stress", "--cases", "nothing-like-this"]) == 1
    assert main(["bench", "stress", "--quick", "--suites", "images", "--renderers", "vtkk"]) == 1
    err = capsys.readouterr().err
    assert "--suites must name" in err and "--size must lie" in err and "no stress case" in err
    assert "unknown renderers ['vtkk']" in err
