"""`python -m benchmarks.objectorder_reach`: how many cells objectorder's pre-integrated
classification leaves visible with the segment reach dilated both ways against one-sided.

Why: a pre-integrated segment is composited at the cell of its later sample, so a cell's value range
is dilated by the cells its earlier sample can lie in; that sample lies toward the eye, so along an
axis whose rays all run one way the dilation need only go that way (`segment_reach`). Fewer visible
cells means fewer cells and samples in every frame. Per scene, at its view and step 0.5, both ways
and one-sided: visible cells in the volume, the cells and samples one frame takes (hidden volume
removal on), the largest pixel difference, and the median of `--frames` turning frames of each,
the two rules' frames interleaved (two renderers, the rule swapped in before each frame) so that
both see the same load.

    python -m benchmarks.objectorder_reach [--shared DIR] [--scenes bonsai/opaque,...] [--size S] [--frames N]
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import numpy as np
from volren_objectorder import ObjectOrderRenderer
from volren_objectorder import renderer as oo

from benchmarks._cli import run
from volren.bench.datasets import sample_datasets, shared_datasets, shared_folder
from volren.model import RenderSettings

#: The renderer's own rule (restored after each scene)
ONE_SIDED = oo.segment_reach
SCENES = (
    "bonsai/opaque,engine/opaque,aneurism/opaque,ironProt/opaque,phantom_ct/sample,bonsai/spiky,engine/smooth"
)


def _both_ways(camera, volume, rays, h: float, clipped: bool = False) -> oo.Reach:
    """The reach before the one-sided rule: the box of cells a step spans, both ways along every axis
    (what the renderer's rule gives a clipped frame too)."""
    return oo.Reach.both_ways(tuple(int(math.ceil(h / s - 1e-9)) for s in volume.spacing))  # type: ignore[arg-type]


def _frames(d, volume, tf, camera, size: int, frames: int) -> tuple[list, list, list]:
    """Both rules' renderers: (rule, renderer, turning frame ms) each, their first frame's counters
    and images; `oo.segment_reach` is left set to whichever rule drew last."""
    renderers, counts, images = [], [], []
    for reach in (_both_ways, ONE_SIDED):  # the renderer's rule swapped in for each frame
        oo.segment_reach = reach
        r = ObjectOrderRenderer()
        r.set_volume(volume)
        r.set_transfer_function(tf)
        r.set_settings(RenderSettings(step=0.5, preintegration=True))
        images.append(r.render(camera, size, size))
        counts.append(dict(r.last_frame.counters))
        renderers.append((reach, r, []))
    for f in range(frames):
        turned = d.camera(volume.bounds, turn=2.0 * (f + 1))
        for reach, r, ms in renderers if f % 2 == 0 else renderers[::-1]:
            oo.segment_reach = reach
            start = time.perf_counter()
            r.render(turned, size, size)
            ms.append((time.perf_counter() - start) * 1000.0)
    for _, r, _ in renderers:
        r.release()
    return renderers, counts, images


def measure(args: argparse.Namespace) -> int:
    shared = shared_folder(args.shared, required=False)
    found = {**(shared_datasets(shared) if shared else {}), **sample_datasets()}
    print(
        "| scene | visible cells, both ways | one-sided | cells taken, both ways | one-sided "
        "| samples, both ways | one-sided | max image difference | ms, both ways | one-sided |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for scene in args.scenes.split(","):
        name, style = scene.split("/")
        d = found[name]
        volume = d.load()
        tf = dict(d.transfer_functions())[style]
        camera = d.camera(volume.bounds)
        try:
            renderers, counts, images = _frames(d, volume, tf, camera, args.size, args.frames)
        finally:
            oo.segment_reach = ONE_SIDED
        b, o = counts
        (_, _, ms_b), (_, _, ms_o) = renderers
        diff = float(np.abs(images[0] - images[1]).max())
        t_b, t_o = statistics.median(ms_b), statistics.median(ms_o)
        print(f"| {scene} | {b['cells_visible']:.0f} | {o['cells_visible']:.0f} ({o['cells_visible'] / b['cells_visible'] - 1:+.0%}) "
              f"| {b['cells']:.0f} | {o['cells']:.0f} ({o['cells'] / b['cells'] - 1:+.0%}) "
              f"| {b['samples']:.0f} | {o['samples']:.0f} ({o['samples'] / b['samples'] - 1:+.0%}) | {diff:.2g} "
              f"| {t_b:.0f} | {t_o:.0f} ({t_o / t_b - 1:+.0%}) |", flush=True)  # fmt: skip
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.objectorder_reach", description=__doc__.split("\n")[0]
    )
    parser.add_argument("--shared", help="the folder with data/ and scenes/ (default: $VOLREN_SHARED)")
    parser.add_argument("--scenes", default=SCENES, help=f"comma-separated dataset/TF (default {SCENES})")
    parser.add_argument("--size", type=int, default=512, help="image side in pixels (default 512)")
    parser.add_argument("--frames", type=int, default=7, help="timed turning frames of each rule (default 7)")
    return run(measure, parser, argv)


if __name__ == "__main__":
    raise SystemExit(main())
