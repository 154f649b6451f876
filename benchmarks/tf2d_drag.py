"""`python -m benchmarks.tf2d_drag --shared ../shared`: what a preview of a dragged 2D TF costs with
raycast's full 2D table and with the drag's smaller one (`table_2d`), and what the smaller table
changes in the image.

Why: while a 2D widget is dragged the TF changes at every preview, so every preview samples the
whole table again (512 x 256 points through every widget) before it marches a ray. For each grid
scene (the hard procedural ones, and bonsai smooth with --shared) the `blob` 2D TF of
`benchmarks.tf2d` (the 1D TF as a band with a Gaussian widget over it, the app's 2D widget
gesture) is drawn at a preview's size and settings (raycast's `interactive` level for the scene,
its `tf_drag_options`), the widget moving along the value axis at each frame, once per table size,
the sizes taking turns. Printed: median ms per frame of each, and the largest pixel difference and
RMSE of the smaller table's image against the full table's at the same widget position.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np

from benchmarks.tf2d import scenes, two_d_tfs
from volren.bench.datasets import shared_folder
from volren.model.scene_class import SceneClass
from volren.model.settings import RenderSettings
from volren.model.transfer_function_2d import TFWidget
from volren.quality import at_level
from volren.renderers.raycast import RaycastRenderer
from volren.renderers.raycast.renderer import OPTIONS

FULL = next(o.default for o in OPTIONS if o.name == "table_2d")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.tf2d_drag", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument(
        "--shared", help="the folder with data/ and scenes/ (default: $VOLREN_SHARED; none: hard scenes only)"
    )
    parser.add_argument("--size", type=int, default=160, help="the preview's width and height (default 160)")
    parser.add_argument("--frames", type=int, default=9, help="frames per table size (default 9)")
    args = parser.parse_args(argv)
    shared = shared_folder(args.shared, required=False)
    drag = dict(RaycastRenderer.capabilities.tf_drag_options)
    small = int(drag["table_2d"])
    command = " ".join(["python -m benchmarks.tf2d_drag", *(argv if argv is not None else sys.argv[1:])])
    print(f"From `{command}`: {args.size}x{args.size}, raycast at its `interactive` level with its tf_drag_options "
          f"{drag}, the Gaussian widget moving at each frame, median of {args.frames} frames per table; load "
          f"average at the start {' '.join(f'{v:.2f}' for v in os.getloadavg())}.")  # fmt: skip
    print()
    print(f"| scene | ms, table {FULL} | ms, table {small} | {FULL} / {small} | largest difference | RMSE |")
    print("|---|---:|---:|---:|---:|---:|")
    ratios = []
    seen = set()
    for scene, volume, tf1, camera in scenes(shared):
        if scene in seen:  # one TF per scene: the first
            continue
        seen.add(scene)
        tf = two_d_tfs(tf1, volume)["blob"]
        base = (
            at_level("raycast", SceneClass.of(volume, tf), "interactive", RenderSettings())
            or RenderSettings()
        )
        lo, hi = tf.value_range
        blob = tf.widgets[-1]
        renderers = {}
        for n in (FULL, small):
            r = RaycastRenderer()
            r.set_volume(volume)
            r.set_transfer_function(tf)
            r.set_settings(base.with_(options={**base.options, **drag, "table_2d": n}))
            renderers[n] = r
        times: dict[int, list[float]] = {FULL: [], small: []}
        diff, squares = 0.0, []
        for k in range(args.frames + 1):
            centre = (lo + (0.3 + 0.4 * k / args.frames) * (hi - lo), blob.center[1])  # type: ignore[index]
            tf.replace_widget(
                len(tf.widgets) - 1, TFWidget.gaussian(centre, blob.width, blob.color, blob.opacity)
            )
            images = {}
            for n in (FULL, small) if k % 2 else (small, FULL):
                start = time.perf_counter()
                images[n] = renderers[n].render(camera, args.size, args.size)
                if k:  # the first frame prepares
                    times[n].append(1000.0 * (time.perf_counter() - start))
            d = images[small].astype(np.float64) - images[FULL]
            diff, squares = max(diff, float(np.abs(d).max())), [*squares, float(np.mean(d**2))]
        full_ms, small_ms = statistics.median(times[FULL]), statistics.median(times[small])
        ratios.append(full_ms / small_ms)
        print(f"| {scene} | {full_ms:.1f} | {small_ms:.1f} | {full_ms / small_ms:.2f} | {diff:.4f} | "
              f"{np.sqrt(np.mean(squares)):.5f} |")  # fmt: skip
    print()
    print(f"{FULL} / {small} over {len(ratios)} scenes: median {statistics.median(ratios):.2f}, "
          f"range {min(ratios):.2f}-{max(ratios):.2f}.")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
