"""Time per frame and error against `reference` for `slicer` and `vtk` in one run (issue 4's table).

For each dataset and TF style in ../shared/scenes: `slicer` post-classified and pre-integrated
(each path asked for) and `vtk` at each step; ms per frame is the median of several frames after
a warm-up frame (compilation, uploads and tables are in the warm-up), the error is DESIGN.md's
RMSE against the `reference` image of the same view, read from the on-disk reference cache (or
rendered once into it). Rows come back as dicts; `markdown` formats them.
"""

from __future__ import annotations

import json
import statistics
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

from volren.api import prepared_renderer
from volren.bench.pareto import equal_error
from volren.bench.reference_cache import reference_image
from volren.bench.vtk_vs_reference import SCENES
from volren.model.camera import Camera
from volren.model.settings import RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.testing.metrics import image_error


@dataclass(frozen=True)
class Config:
    """One renderer setting in the table."""

    label: str
    renderer: str
    settings: RenderSettings


def configs(steps: Iterable[float], paths: Iterable[str]) -> list[Config]:
    out = []
    for step in steps:
        for path in paths:
            for pre in (False, True):
                name = f"slicer {path} {'pre' if pre else 'post'}"
                out.append(Config(name, "slicer", RenderSettings(step=step, preintegration=pre, options={"path": path})))
        out.append(Config("vtk", "vtk", RenderSettings(step=step)))
    return out


def time_frames(renderer, camera: Camera, size: int, frames: int):
    image = renderer.render(camera, size, size)  # warm-up: compilation, uploads, tables
    times = []
    for _ in range(frames):
        start = time.perf_counter()
        image = renderer.render(camera, size, size)
        times.append((time.perf_counter() - start) * 1000.0)
    return statistics.median(times), image, dict(renderer.last_frame.counters)


def run(
    shared: Path,
    datasets: Iterable[str],
    styles: Iterable[str],
    steps: Iterable[float],
    paths: Iterable[str] = ("march",),
    size: int = 512,
    frames: int = 5,
    report: Callable[[dict], None] | None = None,
) -> list[dict]:
    from volren.io import load_volume

    rows = []
    for dataset in datasets:
        path, scalars, az, el, zoom = SCENES[dataset]
        volume = load_volume(shared / "data" / path, scalars=scalars)
        camera = Camera.orbit(volume.bounds, az, el, zoom)
        for style in styles:
            tf = TransferFunction1D.from_dict(json.loads((shared / "scenes" / f"{dataset}-{style}.json").read_text()))
            reference = reference_image(volume, tf, camera, size, size)
            for config in configs(steps, paths):
                with prepared_renderer(config.renderer, volume, tf, config.settings) as renderer:
                    ms, image, counters = time_frames(renderer, camera, size, frames)
                err = image_error(image, reference)
                row = {
                    "dataset": dataset,
                    "tf": style,
                    "renderer": config.label,
                    "step": config.settings.step,
                    "ms": ms,
                    "rmse": err.rmse,
                    "max_abs": err.max_abs,
                    "samples": counters.get("samples", float("nan")),
                }
                rows.append(row)
                if report is not None:
                    report(row)
    return rows


HEADER = "| dataset | TF | renderer | step | ms/frame | RMSE | max abs | samples |\n|---|---|---|---|---|---|---|---|"


def markdown_row(row: dict) -> str:
    samples = row["samples"]
    samples_text = "-" if samples != samples else f"{samples / 1e6:.2f} M"
    return (
        f"| {row['dataset']} | {row['tf']} | {row['renderer']} | {row['step']:g} | {row['ms']:.1f} | "
        f"{row['rmse']:.5f} | {row['max_abs']:.4f} | {samples_text} |"
    )


RATIO_HEADER = (
    "| dataset | TF | vtk step | vtk ms | vtk RMSE | fastest slicer at equal or lower RMSE | its ms | its RMSE | time ratio |\n"
    "|---|---|---|---|---|---|---|---|---|"
)


def equal_error_rows(rows: list[dict]) -> list[str]:
    """For every `vtk` row: the fastest `slicer` row of the same scene whose RMSE is at most
    vtk's, and the ratio of their times (the issue's goal is a ratio of at most 0.5)."""
    out = []
    for peer in (r for r in rows if r["renderer"] == "vtk"):
        scene = [r for r in rows if (r["dataset"], r["tf"]) == (peer["dataset"], peer["tf"])]
        (match,) = equal_error([peer], [r for r in scene if r["renderer"].startswith("slicer")])
        head = f"| {peer['dataset']} | {peer['tf']} | {peer['step']:g} | {peer['ms']:.1f} | {peer['rmse']:.5f} |"
        best = match.ours
        if best is None:
            out.append(head + " none | - | - | - |")
            continue
        out.append(
            head + f" {best['renderer']}, step {best['step']:g} | {best['ms']:.1f} | {best['rmse']:.5f} | "
            f"{match.ratio:.2f} |"
        )
    return out
