"""`python -m benchmarks.objectorder_blocks`: objectorder with its cells drawn in blocks and cell by cell.

Why: the object-order renderer draws the 2 x 2 x 2 cells under an octree node as one
block where they are small on screen and none of the node's pixels is finished (option
`block_pixels`, 0: cell by cell). Both ways take the same samples; this measures what blocks save,
frames of the two interleaved in one process so that both see the same load: 512x512, each scene's
camera turning 2 degrees of azimuth per frame, the median of FRAMES frames per round and the median
of ROUNDS rounds, with the largest pixel difference and the Table 1 counters of both.
"""

from __future__ import annotations

import argparse
import os

import numpy as np

from benchmarks._cli import run
from volren.bench.datasets import shared_datasets, shared_folder
from volren.model import RenderSettings


def measure(args: argparse.Namespace) -> int:
    from volren_objectorder import ObjectOrderRenderer  # the plugin, as the other plugin benchmarks use it

    datasets = shared_datasets(shared_folder(args.shared))
    print(f"load average at the start: {' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    print(
        "| scene | step | cells ms | blocks ms | cells / blocks | max pixel difference | samples (both) "
        "| cells, occluded (cell by cell) | cells, occluded (blocks) |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for case in args.cases.split(","):
        name, style, step = case.split("/")
        data = datasets[name]
        volume = data.load()
        tf = dict(data.transfer_functions())[style]
        renderers = {}
        for label, pixels in (("cells", 0), ("blocks", None)):
            r = ObjectOrderRenderer()
            r.set_volume(volume)
            r.set_transfer_function(tf)
            options = {} if pixels is None else {"block_pixels": pixels}
            r.set_settings(RenderSettings(step=float(step), options=options))
            renderers[label] = r
        images = {label: r.render(data.camera(volume.bounds), 512, 512) for label, r in renderers.items()}
        times: dict[str, list[float]] = {"cells": [], "blocks": []}
        for _ in range(args.rounds):
            for label, r in renderers.items():
                frames = []
                for f in range(args.frames):
                    r.render(data.camera(volume.bounds, turn=2.0 * (f + 1)), 512, 512)
                    frames.append(r.last_frame.ms)
                times[label].append(float(np.median(frames)))
        c, b = (renderers[k].last_frame.counters for k in ("cells", "blocks"))
        t_c, t_b = np.median(times["cells"]), np.median(times["blocks"])
        diff = float(np.abs(images["cells"].astype(np.float64) - images["blocks"]).max())
        samples = (
            f"{c['samples']:.0f}"
            if c["samples"] == b["samples"]
            else f"{c['samples']:.0f} / {b['samples']:.0f}"
        )
        print(f"| {name} {style} | {step} | {t_c:.1f} | {t_b:.1f} | {t_c / t_b:.2f}x | {diff:.1e} | {samples} "
              f"| {c['cells']:.0f}, {c['occluded_ratio'] * 100:.1f} % | {b['cells']:.0f}, {b['occluded_ratio'] * 100:.1f} % |",
              flush=True)  # fmt: skip
        for r in renderers.values():
            r.release()
    print(f"load average at the end: {' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.objectorder_blocks", description=__doc__.split("\n")[0]
    )
    parser.add_argument("--shared", help="the folder with data/ and scenes/ (default: $VOLREN_SHARED)")
    parser.add_argument(
        "--cases",
        default="bonsai/smooth/1,bonsai/smooth/0.5,engine/smooth/1,bonsai/opaque/0.25,"
        "aneurism/opaque/0.25,ironProt/opaque/0.25",
        help="DATASET/TF/STEP,... (default: six)",
    )
    parser.add_argument("--frames", type=int, default=5, help="turning frames per round (default 5)")
    parser.add_argument("--rounds", type=int, default=3, help="rounds, the two ways alternating (default 3)")
    return run(measure, parser, argv)


if __name__ == "__main__":
    raise SystemExit(main())
