"""`python -m benchmarks.zarr_levels`: an OME-Zarr pyramid's cost and what each level buys.

For each shared dataset: the time `save_ome_zarr` takes to write its pyramid (64^3 bricks), the
time `load_level` takes to read each level back, and, per level, a warm frame's time with the
renderer `auto` picks at quality `default` and the frame's RMSE against the full-resolution
frame, both at 512x512, median of `--repeats` frames. The ratio column is the full level's frame
time over that level's: what drawing a coarser level (the level of detail a view needs) saves.

    .venv/bin/python -m benchmarks.zarr_levels --shared ../shared
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import tempfile
import time
from functools import partial
from pathlib import Path

DATASETS = {
    "bonsai": "uniform/bonsai.vti",
    "engine": "uniform/engine.vti",
    "aneurism": "uniform/aneurism.vti",
}


def _median_ms(action, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        action()
        times.append((time.perf_counter() - start) * 1000.0)
    return statistics.median(times)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shared", default=str(Path(__file__).resolve().parents[2] / "shared"))
    parser.add_argument("--datasets", default=",".join(DATASETS))
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--size", type=int, default=512)
    args = parser.parse_args()
    from volren.api import default_transfer_function, prepared_renderer
    from volren.io import load_volume
    from volren.io.ome_zarr_io import load_level, open_multiscale, save_ome_zarr
    from volren.model.camera import Camera
    from volren.model.settings import RenderSettings
    from volren.quality import resolve
    from volren.renderers.base import render_frame
    from volren.testing.metrics import image_error

    print(f"OME-Zarr pyramids, 64^3 bricks; frames {args.size}x{args.size}, median of {args.repeats}")
    print(
        "| dataset | write pyramid, ms | level | dims | read level, ms | renderer | frame, ms | frame ratio, full/level "
        "| RMSE against full |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    folder = Path(tempfile.mkdtemp(prefix="volren-zarr-"))
    try:
        for name in args.datasets.split(","):
            volume = load_volume(Path(args.shared) / "data" / DATASETS[name])
            path = folder / f"{name}.zarr"
            write_ms = _median_ms(partial(save_ome_zarr, volume, path), 1)
            tf = default_transfer_function(volume)
            renderer, settings, _ = resolve("uniform", 1, "auto", "default", RenderSettings())
            camera = Camera.orbit(volume.bounds, 30, 20)
            full_image, full_ms = None, None
            for level in range(len(open_multiscale(path).levels)):
                read_ms = _median_ms(partial(load_level, path, level), args.repeats)
                data = load_level(path, level)
                with prepared_renderer(renderer, data, tf, settings) as r:
                    image, _ = render_frame(r, camera, args.size, args.size)  # warm-up: tables, caches
                    frame_ms = _median_ms(
                        partial(render_frame, r, camera, args.size, args.size), args.repeats
                    )
                if full_image is None:
                    full_image, full_ms = image, frame_ms
                error = image_error(image, full_image).rmse
                dims = "x".join(map(str, data.dimensions))
                print(f"| {name if level == 0 else ''} | {f'{write_ms:.0f}' if level == 0 else ''} | {level} | {dims} | "
                      f"{read_ms:.0f} | {renderer} | {frame_ms:.0f} | {full_ms / frame_ms:.1f}x | {error:.4f} |",
                      flush=True)  # fmt: skip
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
