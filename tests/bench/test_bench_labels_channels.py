"""`volren bench run`'s label and channel scenes (`volren.bench.mixed_datasets`): selected by group
or name and never by default, drawn by the renderers that draw them, refused (not failed) by the
others, and the procedural spheres against their closed form and a float64 brute force."""

from __future__ import annotations

import csv
import math
from collections.abc import Iterator, Mapping
from typing import ClassVar

import numpy as np
import pytest

from volren.bench import datasets, run_bench, sweep
from volren.bench.mixed_datasets import (
    SPHERES_POINTS,
    SPHERES_RADII,
    spheres,
    spheres_axis_alpha,
    spheres_extinctions,
)
from volren.cli.main import main
from volren.renderers.base import Capabilities, KindSupport, RendererBase
from volren.renderers.registry import registry


@pytest.fixture(autouse=True)
def reference_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("VOLREN_REFERENCE_CACHE", str(tmp_path / "cache"))


class OneField(RendererBase):
    """A renderer of uniform grids that declares neither labels nor channels (never drawn here:
    the run refuses it from its capabilities before making one)."""

    name: ClassVar[str] = "one-field"
    capabilities: ClassVar[Capabilities] = Capabilities(
        kinds={"uniform": KindSupport()}, summary="test double"
    )

    def _render(self, camera, width, height, progress) -> tuple[np.ndarray, Mapping[str, float]]:
        raise AssertionError("a refused renderer is never drawn")


@pytest.fixture
def one_field() -> Iterator[str]:
    registry.register(OneField.name, OneField, replace=True)
    try:
        yield OneField.name
    finally:
        registry.unregister(OneField.name)


def test_groups_name_the_scenes_and_the_default_run_leaves_them_out(shared_data, shared_scenes):
    for shared in (None, shared_data.parent):
        default = {d.name for d in datasets.select(None, shared)}
        labels = [d.name for d in datasets.select(["labels"], shared)]
        channels = [d.name for d in datasets.select(["channels"], shared)]
        assert "spheres-labels" in labels and "slab-channels" in channels
        assert not default & {*labels, *channels}
    assert set(labels) == {"pd25-labels", "frog-labels", "spheres-labels"}
    assert set(channels) == {"stroke-channels", "vase-channels", "slab-channels"}
    (one,) = datasets.select(["spheres-labels"], None)
    assert one.styles == ("labels",) and one.kind == "uniform"


def test_the_spheres_centre_line_has_the_closed_form():
    """Along the x grid line through the centre, the `reference` pixel's alpha is the closed form,
    and its colour the float64 integral of the label model over the line's linear label weights."""
    from volren.testing.reference_images import reference_image
    from volren.testing.scenes import axis_camera

    volume, tf = spheres()
    b = volume.bounds
    image = reference_image(volume, tf, axis_camera(b, 0, 1.0, 0.35 * (b[3] - b[2])), 9, 9)
    centre = image[4, 4].astype(np.float64)
    # float64 brute force: the line's labels, each label's weight their linear interpolant
    n, c = SPHERES_POINTS, (SPHERES_POINTS - 1) // 2
    line = spheres()[0].labels.values[c, c, :]
    ds = 1e-3
    s = (np.arange(round((n - 1) / ds)) + 0.5) * ds
    weights = {k: np.interp(s, np.arange(n), (line == k).astype(float)) for k in (0, 1, 2)}
    tau, q = tf.extinction_emission(np.full(s.shape, 0.5), weights)
    through = np.exp(-(np.cumsum(tau) - tau / 2) * ds)
    rgb = (q * through[:, None]).sum(axis=0) * ds
    alpha = -math.expm1(-tau.sum() * ds)
    assert abs(alpha - spheres_axis_alpha()) < 1e-6  # the boundary cells' ramps add up to the radii
    taus = spheres_extinctions()
    assert spheres_axis_alpha() > -math.expm1(-2 * taus[2] * SPHERES_RADII[0]) + 0.1  # the shell shows
    assert np.abs(centre - np.append(rgb, alpha)).max() < 2e-3


@pytest.mark.parametrize(
    ("name", "style", "refused_as"),
    [
        ("spheres-labels", "labels", "does not draw label volumes"),
        ("slab-channels", "channels", "does not mix channels"),
    ],
)
def test_run_measures_the_scene_and_reports_refusals(opengl, one_field, name, style, refused_as):
    class Seen(run_bench.Progress):
        def __init__(self) -> None:
            self.skipped_lines: list[str] = []

        def skipped(self, what: str, reason: str) -> None:
            self.skipped_lines.append(f"{what}: {reason}")

    chosen = datasets.select([name], None)
    configs = sweep.configs("uniform", steps=[1.0], curves=["slicer", one_field, "pyvista"])
    seen = Seen()
    rows = list(run_bench.run(chosen, lambda kind: configs, 24, 1, progress=seen))
    assert rows and {r["renderer"] for r in rows} == {"slicer"}
    assert all(r["dataset"] == name and r["tf"] == style for r in rows)
    assert all(math.isfinite(r["ms"]) and r["rmse"] < 0.05 for r in rows)
    refused = [line for line in seen.skipped_lines if f": {run_bench.REFUSED}" in line]
    assert refused == seen.skipped_lines  # every line a refusal, none a failure
    assert any(f"one-field {refused_as}" in line for line in refused)
    assert any("pyvista draws one field with one 1D TF" in line for line in refused)


def test_bench_run_cli_lists_and_runs_a_label_scene(tmp_path, opengl, one_field):
    pytest.importorskip("matplotlib")
    out = tmp_path / "out"
    code = main(["bench", "run", "--datasets", "spheres-labels", "--renderers", f"slicer,{one_field}",
                 "--steps", "1", "--size", "16", "--frames", "1", "--out", str(out)])  # fmt: skip
    assert code == 0
    with (out / "runs.csv").open(newline="") as stream:
        rows = list(csv.DictReader(stream))
    assert rows and {(r["dataset"], r["tf"], r["renderer"]) for r in rows} == {
        ("spheres-labels", "labels", "slicer")
    }
    summary = (out / "summary.md").read_text()
    assert "## Refused" in summary and "one-field does not draw label volumes" in summary
    assert "## Skipped" not in summary
