"""Time per frame and error against `reference` for `slicer` and `vtk` in one run.

For each dataset and TF style in ../shared/scenes: `slicer` post-classified and pre-integrated
(each path asked for) and `vtk` at each step; ms per frame is the median of several frames after
a warm-up frame (compilation, uploads and tables are in the warm-up), the error is DESIGN.md's
RMSE against the `reference` image of the same view, read from the on-disk reference cache (or
rendered once into it). Rows come back as dicts; `markdown` formats them.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

from benchmarks._cli import float_list
from benchmarks._cli import run as run_command
from volren.api import prepared_renderer
from volren.bench.datasets import SCENES, shared_folder
from volren.bench.pareto import equal_error
from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.settings import RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.testing.metrics import image_error
from volren.testing.reference_images import reference_image


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
                out.append(
                    Config(
                        name, "slicer", RenderSettings(step=step, preintegration=pre, options={"path": path})
                    )
                )
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
            tf = TransferFunction1D.from_dict(
                json.loads((shared / "scenes" / f"{dataset}-{style}.json").read_text())
            )
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
        head = (
            f"| {peer['dataset']} | {peer['tf']} | {peer['step']:g} | {peer['ms']:.1f} | {peer['rmse']:.5f} |"
        )
        best = match.ours
        if best is None:
            out.append(head + " none | - | - | - |")
            continue
        out.append(
            head + f" {best['renderer']}, step {best['step']:g} | {best['ms']:.1f} | {best['rmse']:.5f} | "
            f"{match.ratio:.2f} |"
        )
    return out


def run_table(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    shared = shared_folder(args.shared)
    datasets = [d for d in args.datasets.split(",") if d]
    unknown = [d for d in datasets if d not in SCENES or SCENES[d][0].startswith("tets/")]
    if unknown:
        grids = ", ".join(n for n, s in SCENES.items() if not s[0].startswith("tets/"))
        raise VolrenError(f"unknown or non-uniform datasets {unknown}; choose from {grids}")
    steps = float_list(args.steps, "--steps")
    paths = [p for p in args.paths.split(",") if p]
    if not paths or any(p not in ("march", "slices") for p in paths):
        raise VolrenError(f"--paths must name march and/or slices, got {args.paths!r}")
    if args.size < 8 or args.frames < 1:
        raise VolrenError("--size must be at least 8 and --frames at least 1")
    styles = [s for s in args.styles.split(",") if s]
    total = len(datasets) * len(styles) * len(configs(steps, paths))
    lines = [HEADER]
    print(HEADER)
    with tqdm(total=total, desc="settings", leave=False) as bar:

        def report(row: dict) -> None:
            line = markdown_row(row)
            lines.append(line)
            tqdm.write(line)
            bar.update()

        rows = run(shared, datasets, styles, steps, paths, args.size, args.frames, report)
    ratios = [RATIO_HEADER, *equal_error_rows(rows)]
    lines += ["", *ratios]
    print("\n" + "\n".join(ratios))
    if args.out:
        try:
            Path(args.out).write_text("\n".join(lines) + "\n")
        except OSError as exc:
            raise VolrenError(f"{args.out}: cannot write: {exc.strerror or exc}") from None
    return 0


def main(argv: list[str] | None = None) -> int:
    s = argparse.ArgumentParser(
        prog="python -m benchmarks.slicer_table",
        description="slicer and vtk: ms per frame and RMSE against reference per step",
    )
    s.add_argument("--shared", help="the shared folder with data/ and scenes/ (default: $VOLREN_SHARED)")
    s.add_argument("--datasets", default="bonsai,engine", help="comma-separated (default bonsai,engine)")
    s.add_argument("--styles", default="smooth,spiky,opaque", help="TF styles (default smooth,spiky,opaque)")
    s.add_argument("--steps", default="1,0.5,0.25", help="sample steps (default 1,0.5,0.25)")
    s.add_argument("--paths", default="march", help="slicer paths: march, slices or both (default march)")
    s.add_argument("--size", type=int, default=512, help="image side in pixels (default 512)")
    s.add_argument(
        "--frames", type=int, default=5, help="timed frames per setting, median reported (default 5)"
    )
    s.add_argument("--out", help="also write the table to this Markdown file")
    return run_command(run_table, s, argv)


if __name__ == "__main__":
    sys.exit(main())
