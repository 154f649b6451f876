"""`python -m benchmarks.tf_edit_latency`: from a transfer-function edit to the next frame.

Why: a TF edit is what a user waits on in the editor, and renderers cache what they derive from
the TF (tables, run-length runs, octree classification, textures). For each renderer and shared
scene, the median time of `render` at the scene's view, at 512x512 by default:

- `camera only`: nothing changed but the version-free state (the warm-frame baseline);
- `colour edit`: every colour point's green channel nudged (the opacity support is unchanged, so
  anything keyed on it may be reused);
- `opacity edit`: every opacity point moved by 1 % of the value range, alternately up and down
  (the support moves: what is keyed on it is rebuilt).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable
from functools import partial

import numpy as np

from benchmarks._cli import run
from volren.bench.datasets import shared_datasets, shared_folder
from volren.model.settings import RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.renderers.registry import registry


def _nudge_colour(tf: TransferFunction1D, k: int) -> None:
    points = tf.color_points.copy()
    points[:, 2] = np.clip(points[:, 2] + (0.01 if k % 2 else -0.01), 0.0, 1.0)
    tf.set_color_points(points)


def _move_opacity(tf: TransferFunction1D, k: int, *, span: float) -> None:
    points = tf.opacity_points.copy()
    points[:, 0] += (0.01 if k % 2 == 0 else -0.01) * span
    tf.set_opacity_points(points)


def _median_ms(renderer, camera, size: int, edits: int, edit: Callable[[int], None] | None) -> float:
    times = []
    for k in range(edits):
        if edit is not None:
            edit(k)
        start = time.perf_counter()
        renderer.render(camera, size, size)
        times.append((time.perf_counter() - start) * 1000.0)
    return statistics.median(times)


def measure(args: argparse.Namespace) -> int:
    datasets = shared_datasets(shared_folder(args.shared))
    names = [n for n in args.datasets.split(",") if n]
    print(f"| renderer | scene | camera only ms | colour edit ms | opacity edit ms | (median of {args.edits}, "
          f"{args.size}x{args.size}) |")  # fmt: skip
    print("|---|---|---:|---:|---:|---|")
    for name in names:
        dataset = datasets[name]
        volume = dataset.load()
        lo, hi = volume.value_range
        camera = dataset.camera(volume.bounds)
        for style, scene_tf in dataset.transfer_functions():
            if style not in args.styles.split(","):
                continue
            for renderer_name in [r for r in args.renderers.split(",") if r]:
                tf = scene_tf.copy()
                renderer = registry.create(renderer_name)
                try:
                    renderer.set_volume(volume)
                    renderer.set_transfer_function(tf)
                    renderer.set_settings(RenderSettings(preintegration=args.preintegration))
                    renderer.render(camera, args.size, args.size)  # warm: compilation, uploads, tables
                    still = _median_ms(renderer, camera, args.size, args.edits, None)
                    colour = _median_ms(renderer, camera, args.size, args.edits, partial(_nudge_colour, tf))
                    opacity = _median_ms(renderer, camera, args.size, args.edits,
                                         partial(_move_opacity, tf, span=hi - lo))  # fmt: skip
                finally:
                    renderer.release()
                print(
                    f"| {renderer_name} | {name} {style} | {still:.0f} | {colour:.0f} | {opacity:.0f} | |",
                    flush=True,
                )
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.tf_edit_latency", description=__doc__.split("\n")[0]
    )
    parser.add_argument("--shared", help="the folder with data/ and scenes/ (default: $VOLREN_SHARED)")
    parser.add_argument(
        "--renderers", default="shearwarp,slicer,vtk", help="comma-separated (default shearwarp,slicer,vtk)"
    )
    parser.add_argument(
        "--datasets", default="bonsai", help="comma-separated shared datasets (default bonsai)"
    )
    parser.add_argument("--styles", default="smooth", help="comma-separated TF styles (default smooth)")
    parser.add_argument("--size", type=int, default=512, help="image side in pixels (default 512)")
    parser.add_argument(
        "--edits", type=int, default=5, help="timed frames per kind of edit, median (default 5)"
    )
    parser.add_argument("--preintegration", action="store_true", help="pre-integrated TFs (default: the renderer's "
                        "settings default, post-classified)")  # fmt: skip
    return run(measure, parser, argv)


if __name__ == "__main__":
    sys.exit(main())
