"""A Markdown table with a row per scene of the shared datasets and the bundled samples, printed as
it grows and written to a BENCHMARKS.md fragment: what `benchmarks.defaults_ab`,
`benchmarks.fastest_peer` and `benchmarks.viewer_peers` share (their arguments, the datasets'
loop, the load averages, the renderer a render with no options picks, a timed frame)."""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from benchmarks._cli import run
from volren.bench.datasets import Dataset, sample_datasets, shared_datasets, shared_folder
from volren.model import RenderSettings
from volren.model.scene_class import SceneClass
from volren.quality import resolve
from volren.renderers.base import render_frame

#: (dataset, its volume, TF style, TF, size, frames) -> the scene's row
SceneRow = Callable[[Dataset, Any, str, Any, int, int], str]


def parser(prog: str, description: str, frames: int, fragment: str) -> argparse.ArgumentParser:
    """The arguments both take: --shared, --datasets, --size, --frames (default `frames`), --out."""
    out = argparse.ArgumentParser(prog=prog, description=description)
    out.add_argument("--shared", help="the folder with data/ and scenes/ (default: $VOLREN_SHARED; without "
                                      "it, the bundled samples only)")  # fmt: skip
    out.add_argument("--datasets", default="", help="comma-separated datasets (default: every one)")
    out.add_argument("--size", type=int, default=512, help="image side in pixels (default 512)")
    out.add_argument(
        "--frames", type=int, default=frames, help=f"timed frame pairs per scene, median (default {frames})"
    )
    out.add_argument(
        "--out", help=f"also write the table to this Markdown file (BENCHMARKS.md's fragment: {fragment})"
    )
    return out


def _load() -> str:
    return " ".join(f"{v:.2f}" for v in os.getloadavg())


def scene_table(
    args: argparse.Namespace,
    intro: str,
    header: tuple[str, str],
    row: SceneRow,
    kinds: tuple[str, ...] | None = None,
) -> int:
    """`intro`, the load average, the table (`header`: its two first lines) with `row` for every TF
    of every dataset asked for (of `kinds` only, when given: the others are not even loaded), and
    the load average at the end; printed, and written to --out."""
    shared = shared_folder(args.shared, required=False)
    found = {**(shared_datasets(shared) if shared else {}), **sample_datasets()}
    names = args.datasets.split(",") if args.datasets else list(found)
    if kinds is not None:
        names = [n for n in names if found[n].kind in kinds]
    lines = [intro, "", f"load average at the start: {_load()}", "", *header]
    for line in lines:
        print(line)
    for name in names:
        d = found[name]
        volume = d.load()
        for style, tf in d.transfer_functions():
            lines.append(row(d, volume, style, tf, args.size, args.frames))
            print(lines[-1], flush=True)
    lines += ["", f"load average at the end: {_load()}"]
    print(lines[-1])
    if args.out:
        Path(args.out).write_text("\n".join(lines) + "\n")
    return 0


def named_scene_table(args: argparse.Namespace, intro: str, header: tuple[str, str],
                      rows: Iterator[tuple[str, Callable[[], str]]]) -> int:  # fmt: skip
    """`scene_table` for scenes that are not the datasets': `intro`, the load averages, and the table
    (`header`) with the row of every (name, row maker) of `rows` whose dataset (the name before its
    "/") --datasets asks for; printed as it grows and written to --out."""
    lines = [intro, "", f"load average at the start: {_load()}", "", *header]
    for line in lines:
        print(line, flush=True)
    for name, row in rows:
        if args.datasets and name.split("/")[0] not in args.datasets.split(","):
            continue
        lines.append(row())
        print(lines[-1], flush=True)
    lines += ["", f"load average at the end: {_load()}"]
    print(lines[-1])
    if args.out:
        Path(args.out).write_text("\n".join(lines) + "\n")
    return 0


def no_options_choice(volume: Any, tf: Any, camera: Any) -> tuple[str, RenderSettings]:
    """(renderer, settings) that `volren render` picks with no options (`auto` at quality `default`)."""
    name, settings, _ = resolve(SceneClass.of(volume, tf), tf.dims, "auto", "default", RenderSettings(),
                                cameras=(camera,), bounds=volume.bounds)  # fmt: skip
    return name, settings


def timed_frame(renderer: Any, camera: Any, size: int) -> tuple[float, Any]:
    """(milliseconds, image) of one size x size frame."""
    start = time.perf_counter()
    image, _ = render_frame(renderer, camera, size, size)
    return (time.perf_counter() - start) * 1000.0, image


def ms_text(value: float) -> str:
    """Milliseconds as a table shows them: whole from 100, else three figures."""
    return f"{value:.0f}" if value >= 100 else f"{value:.3g}"


def table_main(module: str, doc: str, frames: int, measure: Callable[[argparse.Namespace], int],
               argv: list[str] | None) -> int:  # fmt: skip
    """`python -m benchmarks.MODULE`: its arguments (`parser`), run by `measure`."""
    fragment = f"docs/bench/{module}.md"
    return run(measure, parser(f"python -m benchmarks.{module}", doc.split("\n")[0], frames, fragment), argv)
