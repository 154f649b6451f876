"""`python -m benchmarks.tetra_walk --shared ../shared`: tetra's C cell walk against its numba walk,
frame for frame, on every mesh scene (the shared meshes' TFs and the bundled sample).

Why: tetra walks its rays in C (`volren/renderers/tetra/walk.c`) where a compiler is found and keeps
numba's walk for machines without one; both must draw the same image, and the C walk must earn its
place by time. Each scene is drawn by tetra with the settings a render with no options gives it
(`auto` at quality `default`), warm, the scene's camera turning 2 degrees a frame, the two walks taking turns
frame by frame. Printed per scene: the median ms of each, their ratio, the largest pixel
difference, and the C frame's cell steps with the nanoseconds each took per core.
"""

from __future__ import annotations

import argparse
import os
import statistics
from typing import Any

import numpy as np

from benchmarks.scene_table import ms_text, no_options_choice, scene_table, table_main, timed_frame
from volren.bench.datasets import Dataset

FRAMES = 5


def _row(dataset: Dataset, volume: Any, style: str, tf: Any, size: int, frames: int) -> str:
    from volren.api import prepared_renderer
    from volren.model import Camera
    from volren.renderers.tetra import walk_native

    def view(turn: float) -> Camera:
        return Camera.orbit(volume.bounds, dataset.azimuth + turn, dataset.elevation, dataset.zoom)

    camera = view(0.0)
    _, settings = no_options_choice(volume, tf, camera)
    settings = settings.with_(options={**settings.options, "backend": "cpu"})
    times: dict[str, list[float]] = {"c": [], "numba": []}
    diff = 0.0
    with prepared_renderer("tetra", volume, tf, settings) as renderer:
        timed_frame(renderer, camera, size)
        with walk_native.numba_only():
            timed_frame(renderer, camera, size)
        for k in range(frames):
            turned = view(2.0 * (k + 1))
            ms, image_c = timed_frame(renderer, turned, size)
            times["c"].append(ms)
            steps = renderer.last_frame.counters["cell_steps"]
            with walk_native.numba_only():
                ms, image_n = timed_frame(renderer, turned, size)
            times["numba"].append(ms)
            diff = max(diff, float(np.abs(image_c - image_n).max()))
    c_ms, n_ms = statistics.median(times["c"]), statistics.median(times["numba"])
    cores = os.cpu_count() or 1
    per_step = c_ms * 1e6 * cores / max(steps, 1)
    return (f"| {dataset.name} | {style} | {ms_text(n_ms)} | {ms_text(c_ms)} | {n_ms / c_ms:.2f} | {diff:.1e} | "
            f"{steps / 1e6:.2f} | {per_step:.0f} |")  # fmt: skip


def measure(args: argparse.Namespace) -> int:
    from volren.renderers.tetra import walk_native

    if not walk_native.available(1):
        print("no C library here (no compiler, or VOLREN_NATIVE=0): numba's walk is the only one")
        return 1
    intro = (f"Measured by `python -m benchmarks.tetra_walk --shared ../shared --size {args.size} --frames "
             f"{args.frames}`: tetra's C walk against numba's, {args.size}x{args.size}, the settings of a render "
             f"with no options, warm, median of {args.frames} turning frames each, the walks in turns; "
             f"{os.cpu_count()} cores. *ns per step* is the C frame's time per cell step and core.")  # fmt: skip
    header = ("| dataset | TF | numba ms | C ms | numba / C | largest difference | M cell steps | ns per step |",
              "|---|---|---:|---:|---:|---:|---:|---:|")  # fmt: skip
    return scene_table(args, intro, header, _row, kinds=("tet",))


def main(argv: list[str] | None = None) -> int:
    return table_main("tetra_walk", __doc__ or "", FRAMES, measure, argv)


if __name__ == "__main__":
    raise SystemExit(main())
