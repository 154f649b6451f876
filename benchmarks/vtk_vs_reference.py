"""Measure the `vtk` renderer against `reference` on the shared scenes (python -m benchmarks.vtk_vs_reference).

For each dataset and TF style in the shared scenes folder (--shared or $VOLREN_SHARED): the RMSE / max / PSNR of `vtk` against
`reference`, the median time per frame of `vtk` (after a warm-up frame) and the time of the one
reference frame (rendered anew, not from the cache). Prints a Markdown table.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

from volren.api import prepared_renderer
from volren.bench.datasets import SCENES, STYLES, shared_folder
from volren.model.camera import Camera
from volren.model.settings import RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.testing.metrics import image_error


def time_frames(renderer, camera, width, height, frames: int) -> tuple[float, object]:
    image = renderer.render(camera, width, height)  # warm-up: uploads, compilation
    times = []
    for _ in range(frames):
        start = time.perf_counter()
        image = renderer.render(camera, width, height)
        times.append((time.perf_counter() - start) * 1000.0)
    return statistics.median(times), image


def main(argv: list[str] | None = None) -> None:
    from volren.io import load_volume

    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--shared", help="the folder with data/ and scenes/ (default: $VOLREN_SHARED)")
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--datasets", default=",".join(SCENES))
    parser.add_argument("--styles", default=",".join(STYLES))
    parser.add_argument("--frames", type=int, default=5)
    parser.add_argument("--step", type=float, default=0.5)
    args = parser.parse_args(argv)
    shared = shared_folder(args.shared)
    size = args.size
    print("| dataset | TF | vtk ms/frame | reference ms | RMSE | max abs | PSNR dB |")
    print("|---|---|---|---|---|---|---|")
    for dataset in args.datasets.split(","):
        path, scalars, az, el, zoom = SCENES[dataset]
        volume = load_volume(shared / "data" / path, scalars=scalars)
        camera = Camera.orbit(volume.bounds, az, el, zoom)
        for style in args.styles.split(","):
            tf = TransferFunction1D.from_dict(
                json.loads((shared / "scenes" / f"{dataset}-{style}.json").read_text())
            )
            settings = RenderSettings(step=args.step)
            start = time.perf_counter()
            with prepared_renderer("reference", volume, tf) as reference_renderer:
                reference = reference_renderer.render(camera, size, size)
            ref_ms = (time.perf_counter() - start) * 1000.0
            with prepared_renderer("vtk", volume, tf, settings) as renderer:
                ms, image = time_frames(renderer, camera, size, size, args.frames)
            err = image_error(image, reference)
            print(
                f"| {dataset} | {style} | {ms:.1f} | {ref_ms:.0f} | {err.rmse:.5f} | {err.max_abs:.4f} | {err.psnr:.1f} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
