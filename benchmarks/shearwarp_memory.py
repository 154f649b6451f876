"""`python -m benchmarks.shearwarp_memory [DATASETS] [--shared DIR]`: what shear-warp's classified
volume (`volren_shearwarp.classified`) holds and costs, per shared uniform dataset (its build
time and memory, the three copies against the raw volume).

Per dataset, with its smooth TF: the raw volume's size; the three axis copies (one per principal
axis, made when a view first needs that axis; uint8 data as it is, where the one along z is the
volume itself, anything else float32): the memory they add and its ratio to the raw volume; the block
ranges cached per copy (two bytes a block, kept across TF edits) and the runs, both for every slice
at run extent 1 (`run_extent` at step 0.5 for a shear up to 1); each axis's copy time, its ranges
pass (once per axis and extent: what a camera turning onto a new axis pays) and its runs rebuild
after an opacity edit that changes the support (what a TF edit pays; colour edits rebuild nothing).
Times are single calls after a warm-up on a small volume (compilation excluded), in ms."""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np
from volren_shearwarp.classified import ClassifiedVolume, OpacitySupport, block_ranges, build_runs, slab_pairs

from volren.bench.datasets import shared_datasets
from volren.model import TransferFunction1D, UniformVolume

MIB = 1024.0 * 1024.0


def _support(volume: UniformVolume, tf: TransferFunction1D) -> OpacitySupport:
    """The support over the span the renderer takes it over (`ShearWarpRenderer._render`): the data's range."""
    return OpacitySupport.of(tf, *volume.value_range)


def _edited(tf: TransferFunction1D, volume: UniformVolume) -> TransferFunction1D:
    """The TF with its opacity points moved up by 5 % of the data's range: a drag that changes the support."""
    lo, hi = volume.value_range
    opacity = tf.opacity_points.copy()
    opacity[:, 0] += 0.05 * (hi - lo)
    return TransferFunction1D(tf.color_points, opacity, tf.opacity_unit_distance)


def _measure(volume: UniformVolume, tf: TransferFunction1D, extent: int) -> dict[str, object]:
    classified = ClassifiedVolume(volume)
    support, moved = _support(volume, tf), _support(volume, _edited(tf, volume))
    copy_ms, ranges_ms, rebuild_ms, ranges_bytes, runs_bytes = [], [], [], 0, 0
    for axis in range(3):
        copy = classified.copy(axis)
        copy_ms.append(classified.copy_ms[axis])
        pairs = slab_pairs(np.arange(copy.values.shape[0]))[0]
        start = time.perf_counter()
        ranges = block_ranges(copy.values, support, extent, pairs)
        ranges_ms.append((time.perf_counter() - start) * 1e3)
        runs = build_runs(ranges, support, extent)
        start = time.perf_counter()
        build_runs(ranges, moved, extent)
        rebuild_ms.append((time.perf_counter() - start) * 1e3)
        ranges_bytes += sum(r.nbytes for r in ranges)
        runs_bytes += runs.nbytes
    # the copy along z is the volume itself where its type is kept (`copy_dtype`): no memory of its own
    copies = sum(
        c.values.nbytes for c in classified.copies.values() if not np.shares_memory(c.values, volume.values)
    )
    return {"copies": copies, "ranges": ranges_bytes, "runs": runs_bytes, "copy_ms": copy_ms,
            "ranges_ms": ranges_ms, "rebuild_ms": rebuild_ms}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.shearwarp_memory", description=__doc__.split("\n")[0]
    )
    parser.add_argument("datasets", nargs="?", default="bonsai,engine,aneurism,ironProt")
    parser.add_argument("--shared", type=Path, default=Path(os.environ.get("VOLREN_SHARED", "../shared")))
    parser.add_argument(
        "--extent", type=int, default=1, help="run extent (cells a ray moves per slab, rounded up)"
    )
    args = parser.parse_args(argv)
    datasets = shared_datasets(args.shared)
    # compile the kernels first, on a small volume
    small = UniformVolume(np.random.default_rng(0).random((9, 10, 11), dtype=np.float32))
    _measure(small, TransferFunction1D.ramp(0.2, 0.8), args.extent)
    ms = lambda values: ", ".join(f"{v:.0f}" for v in values)  # noqa: E731
    print(f"| dataset | raw | axis copies | block ranges | runs (extent {args.extent}) | copy ms (x, y, z) "
          "| ranges ms | runs rebuild ms |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|")
    for name in args.datasets.split(","):
        data = datasets[name]
        volume = data.load()
        tf = dict(data.transfer_functions())["smooth"]
        m = _measure(volume, tf, args.extent)
        raw = volume.values.nbytes
        shape = "x".join(str(n) for n in volume.values.shape[::-1])
        print(f"| {name} | {shape} {volume.values.dtype}, {raw / MIB:.1f} MiB | {m['copies'] / MIB:.1f} MiB "
              f"({m['copies'] / raw:.0f}x) | {m['ranges'] / MIB:.1f} MiB | {m['runs'] / MIB:.2f} MiB "
              f"| {ms(m['copy_ms'])} | {ms(m['ranges_ms'])} | {ms(m['rebuild_ms'])} |", flush=True)  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
