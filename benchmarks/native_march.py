"""`python -m benchmarks.native_march --shared ../shared`: raycast's C march against its numba march,
frame for frame, on the shared grids and the hard uniform cases.

Why: raycast draws 1D TFs with a C march (`volren/renderers/raycast/march.c`) where a compiler is
found and keeps numba's for machines without one; both must draw the same image, and the C march
must earn its place by time. Each scene is drawn at 512x512 with no options (the level `auto` and
the renderer set: raycast's default, its error-targeted step), warm, the camera turning 2 degrees a
frame, the two kernels taking turns frame by frame; the shared grids and hard cases are 8-bit, the
bundled samples float32 and int16 (raycast marches both as float32). The `2d blob` scenes are
2D TFs (value x gradient magnitude: the 1D TF as a band with a Gaussian widget over it, the app's
2D widget gesture; `benchmarks.tf2d`'s `blob`) on bonsai smooth and the hard cases. Printed per scene: the median ms of each, their
ratio, the largest pixel difference, and the C march's counters (samples, segments skipped, rays
terminated early) with its samples per second per core.
"""

from __future__ import annotations

import argparse
import datetime
import os
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from volren.bench.datasets import SCENES, hard_datasets, sample_datasets, scene_inputs, shared_folder

GRIDS = ("bonsai", "engine", "aneurism", "ironProt")
STYLES = ("smooth", "spiky", "opaque")


def scenes(shared: Path | None) -> Iterator[tuple[str, object, object]]:
    """(name, volume or path, TF or path) of every scene: the shared grids' TFs, the hard cases, the
    samples, then the 2D TFs."""
    from benchmarks.tf2d import two_d_tfs

    if shared is not None:
        for dataset in GRIDS:
            for style in STYLES:
                yield (
                    f"{dataset}/{style}",
                    shared / "data" / SCENES[dataset][0],
                    shared / "scenes" / f"{dataset}-{style}.json",
                )
    for name, hard in hard_datasets().items():
        if hard.kind == "uniform":
            volume = hard.load()
            yield f"{name}/hard", volume, next(hard.transfer_functions())[1]
    for name, sample in sample_datasets().items():  # a float32 and an int16 grid (drawn as float32)
        if sample.kind == "uniform":
            yield f"{name}/sample", sample.load(), sample.tf_paths[0][1]
    if shared is not None:
        volume, tf = scene_inputs(shared, "bonsai", "smooth")
        yield "bonsai/smooth/2d blob", volume, two_d_tfs(tf, volume)["blob"]
    for name, hard in hard_datasets().items():
        if hard.kind == "uniform":
            volume = hard.load()
            yield f"{name}/2d blob", volume, two_d_tfs(next(hard.transfer_functions())[1], volume)["blob"]


def compare(volume: object, tf: object, frames: int, size: int) -> dict[str, float]:
    """Median ms of the C and numba marches over `frames` turning frames each (in turns), the
    largest pixel difference, and the C frames' counters."""
    import volren
    from volren.renderers.raycast.march_native import numba_only

    drawing = volren.drawing(volume, tf, renderer="raycast", size=(size, size), azimuth=30, elevation=20)
    times: dict[str, list[float]] = {"c": [], "numba": []}
    diff = 0.0
    with drawing:
        drawing.frame()
        with numba_only():
            drawing.frame()
        for k in range(frames):
            camera = drawing.orbit(azimuth=30 + 2 * (k + 1), elevation=20)
            start = time.perf_counter()
            image_c, stats, *_ = drawing.frame(camera)
            times["c"].append(time.perf_counter() - start)
            with numba_only():
                start = time.perf_counter()
                image_n, *_ = drawing.frame(camera)
                times["numba"].append(time.perf_counter() - start)
            diff = max(diff, float(np.abs(image_c - image_n).max()))
    counters = stats.counters
    c_ms, n_ms = (1e3 * float(np.median(times[key])) for key in ("c", "numba"))
    return {"c_ms": c_ms, "numba_ms": n_ms, "diff": diff, "samples": counters["samples"],
            "skipped": counters.get("segments_skipped", 0.0), "terminated": counters.get("rays_terminated", 0.0),
            "rays": counters.get("rays_cast", 0.0)}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.native_march", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("--shared", help="the folder with data/ and scenes/ (default: $VOLREN_SHARED)")
    parser.add_argument("--frames", type=int, default=5, help="frames per kernel and scene (default 5)")
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--scenes", help="comma-separated names to keep (e.g. bonsai/smooth,hard_tubes/hard)")
    parser.add_argument(
        "--out", help="also write the table to this Markdown file (docs/bench/native_march.md)"
    )
    args = parser.parse_args(argv)
    from volren.renderers.raycast.march_native import vector_path

    shared = shared_folder(args.shared, required=False)
    keep = set(args.scenes.split(",")) if args.scenes else None
    cores = os.cpu_count() or 1
    lines: list[str] = []

    def say(line: str = "") -> None:
        lines.append(line)
        print(line, flush=True)

    say(f"Measured {datetime.date.today()} by `python -m benchmarks.native_march --shared ../shared --frames "
        f"{args.frames}`: raycast's C march ({'AVX2 vector path' if vector_path() else 'no C library: numba only'}) "
        f"against numba's; {args.size}x{args.size}, no options, median of {args.frames} turning frames each, "
        f"{cores} cores.")  # fmt: skip
    say()
    say("| scene | numba ms | C ms | numba / C | largest difference | M samples | segments skipped | "
        "rays terminated early | C M samples/s per core |")  # fmt: skip
    say("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    ratios = []
    for name, volume, tf in scenes(shared):
        if keep is not None and name not in keep:
            continue
        row = compare(volume, tf, args.frames, args.size)
        ratio = row["numba_ms"] / row["c_ms"]
        ratios.append(ratio)
        rate = row["samples"] / (row["c_ms"] / 1e3) / cores / 1e6
        say(f"| {name} | {row['numba_ms']:.0f} | {row['c_ms']:.0f} | {ratio:.2f} | {row['diff']:.1e} | "
            f"{row['samples'] / 1e6:.2f} | {row['skipped'] / 1e6:.2f} M | {row['terminated'] / max(row['rays'], 1):.0%} | "
            f"{rate:.1f} |")  # fmt: skip
    if ratios:
        say()
        say(f"numba / C over {len(ratios)} scenes: median {np.median(ratios):.2f}, "
            f"range {min(ratios):.2f}-{max(ratios):.2f}.")  # fmt: skip
    if args.out:
        Path(args.out).write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
