"""`volren bench skip` on the bundled samples: each skipping technique must save work where it can,
change the image by no more than it is allowed to (exact, or 1 - termination_alpha for early
termination), and the command must write its CSV and Markdown."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

from volren.bench import skipping
from volren.cli.main import main
from volren.model.camera import Camera
from volren.model.settings import RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import UniformVolume
from volren.samples import hollow_cylinder

GREY = [[-1.0, 1.0, 1.0, 1.0], [2.0, 1.0, 1.0, 1.0]]


def ball(n: int = 48) -> UniformVolume:
    """1 - distance from the centre of [-1, 1]^3: a ball in a box, empty around it."""
    t = np.linspace(-1.0, 1.0, n)
    z, y, x = np.meshgrid(t, t, t, indexing="ij")
    return UniformVolume(
        (1.0 - np.sqrt(x * x + y * y + z * z)).astype(np.float32), (t[1] - t[0],) * 3, (-1.0,) * 3
    )


def _scene(name: str, volume, tf: TransferFunction1D) -> skipping.Scene:
    return skipping.Scene(name, "opaque", volume, tf, Camera.orbit(volume.bounds, 30, 20, 1.0))


@pytest.fixture(scope="module")
def rows(opengl) -> dict[tuple[str, str], dict]:
    """Every row of one small run, by (renderer, variant)."""
    # transparent outside radius 0.5, opaque inside 0.4: empty bricks around it, rays stopping on it
    sphere = _scene("ball", ball(), TransferFunction1D(GREY, [[-1.0, 0.0], [0.5, 0.0], [0.6, 1.0]], 0.05))
    # values below 0.8 transparent, above 1 opaque
    cyl_tf = TransferFunction1D(GREY, [[-1.0, 0.0], [0.8, 0.0], [1.0, 1.0]], 0.1)
    cyl = _scene("hollow_cylinder", hollow_cylinder(), cyl_tf)
    out = skipping.run(
        [sphere, cyl], ["slicer", "tetra", "raycast"], size=40, frames=2, turn=1.0, base=RenderSettings()
    )
    return {(r["renderer"], r["variant"]): r for r in out}


def test_each_technique_saves_work(rows):
    """Switching a technique off alone must cost work: the counters are the oracle of what ran."""
    s = {v: rows["slicer", v] for v in ("all_on", "no_empty_space", "no_early_termination", "all_off")}
    assert s["all_on"]["samples"] < s["no_empty_space"]["samples"] <= s["all_off"]["samples"]
    assert s["all_on"]["samples"] < s["no_early_termination"]["samples"] <= s["all_off"]["samples"]
    assert s["all_on"]["rays_terminated"] > 0 and s["no_early_termination"]["rays_terminated"] == 0
    assert s["all_on"]["brick_steps"] > 0 and s["no_empty_space"]["brick_steps"] == 0
    t = {v: rows["tetra", v] for v in ("all_on", "no_transparent_skip", "no_early_termination", "all_off")}
    assert t["all_on"]["cells_integrated"] < t["no_transparent_skip"]["cells_integrated"]
    # rays jump over transparent runs instead of stepping through them
    assert t["all_on"]["cell_steps"] < t["no_transparent_skip"]["cell_steps"]
    assert t["all_on"]["cell_steps"] < t["no_early_termination"]["cell_steps"] < t["all_off"]["cell_steps"]
    assert t["all_off"]["cells_integrated"] >= max(
        t["no_transparent_skip"]["cells_integrated"], t["no_early_termination"]["cells_integrated"]
    )
    assert t["all_on"]["cells_transparent"] > 0 and t["no_transparent_skip"]["cells_transparent"] == 0
    r = {v: rows["raycast", v] for v in ("all_on", "no_empty_space", "no_early_termination", "all_off")}
    assert r["all_on"]["samples"] < r["no_empty_space"]["samples"] <= r["all_off"]["samples"]
    assert r["all_on"]["samples"] < r["no_early_termination"]["samples"] <= r["all_off"]["samples"]
    assert ("raycast", "shading") not in rows  # no shading: the capabilities say so


@pytest.mark.parametrize("renderer", ["slicer", "tetra", "raycast"])
def test_images_within_the_documented_tolerance(rows, renderer):
    """Empty space and transparent cells add nothing: exact; an early stop leaves at most the
    remaining transparency, 1 - 0.999, in any channel (the renderers' default termination_alpha)."""
    stops_early = {
        "all_on": True,
        "no_empty_space": True,
        "no_transparent_skip": True,
        "tf_edit": True,
        "no_early_termination": False,
        "all_off": False,
    }
    for variant, stops in stops_early.items():
        if (renderer, variant) not in rows:
            continue
        row = rows[renderer, variant]
        allowed_on = 1e-5 + (0.0 if stops else 1e-3)
        allowed_off = 1e-5 + (1e-3 if stops else 0.0)
        assert row["max_abs_vs_all_on"] <= allowed_on, (variant, row["max_abs_vs_all_on"])
        assert row["max_abs_vs_all_off"] <= allowed_off, (variant, row["max_abs_vs_all_off"])
        assert row["rmse_vs_all_on"] <= row["max_abs_vs_all_on"]
        assert math.isclose(row["bound_vs_all_on"], allowed_on) and math.isclose(
            row["bound_vs_all_off"], allowed_off
        )
    if renderer == "raycast":
        return  # no shading
    shaded = rows[renderer, "shading"]
    assert shaded["max_abs_vs_all_on"] > 0.01 and math.isnan(shaded["bound_vs_all_on"])


def test_tables_are_rebuilt_only_after_a_tf_edit(rows):
    """The slicer's upload counters: nothing while only the camera turns, tables and the brick mask
    once per frame after each TF edit."""
    assert rows["slicer", "all_on"]["uploaded_tables_per_frame"] == 0
    assert rows["slicer", "all_on"]["uploaded_brick_mask_per_frame"] == 0
    assert rows["slicer", "tf_edit"]["uploaded_tables_per_frame"] == 1
    assert rows["slicer", "tf_edit"]["uploaded_brick_mask_per_frame"] == 1
    for (renderer, variant), row in rows.items():
        assert row["ms_min"] <= row["ms"] <= row["ms_max"] and row["ms_min"] > 0, (renderer, variant)


def test_cli_writes_csv_and_markdown(tmp_path, capsys, renders_with_vtk):
    out = tmp_path / "skip"
    args = ["bench", "skip", "--samples", "--quick", "--size", "24", "--frames", "1", "--out", str(out)]
    assert main(args) == 0
    printed = capsys.readouterr().out
    with (out / "skip.csv").open() as f:
        table = list(csv.DictReader(f))
    for column in (
        "dataset",
        "tf",
        "renderer",
        "variant",
        "ms",
        "samples",
        "brick_steps",
        "rays_terminated",
        "cell_steps",
        "cells_integrated",
        "max_abs_vs_all_on",
        "rmse_vs_all_on",
        "max_abs_vs_all_off",
        "rmse_vs_all_off",
    ):
        assert column in table[0], column
    found = {(r["dataset"], r["renderer"], r["variant"]) for r in table}
    # phantom_ct: slicer (6 rows), vtk (3), the shearwarp and objectorder plugins (6 each) and raycast
    # (5: no shading); hollow_cylinder: tetra (6) and vtk without shading (2)
    assert (
        len(table) == 34
        and ("phantom_ct", "raycast", "shading") not in found
        and ("hollow_cylinder", "vtk", "shading") not in found
    )
    assert ("phantom_ct", "shearwarp", "no_early_termination") in found
    assert ("phantom_ct", "objectorder", "no_hidden_volume_removal") in found
    assert ("phantom_ct", "raycast", "no_empty_space") in found
    assert ("phantom_ct", "slicer", "no_empty_space") in found and (
        "hollow_cylinder",
        "tetra",
        "all_off",
    ) in found
    assert all(float(r["ms"]) > 0 for r in table)
    text = (out / "skip.md").read_text()
    assert "| renderer | technique |" in text and text.count("| phantom_ct | sample | slicer |") == 6
    assert "| slicer | empty-space skipping | samples |" in printed


@pytest.mark.parametrize(
    "bad", [["--renderers", "nope"], ["--samples", "--datasets", "nope"], ["--size", "2"]]
)
def test_cli_refuses_bad_arguments(bad, capsys):
    assert main(["bench", "skip", "--quick", "--frames", "1", *bad]) == 1
    assert "volren: error:" in capsys.readouterr().err
