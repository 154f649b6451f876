"""`python -m benchmarks.resampling_floor`: the error that resampling alone costs, scene by scene.

Why: shear-warp composites rays through the intermediate image's pixel centres and
resamples the result in its warp; `reference` and DESIGN.md's error metric take one ray through
each output pixel's centre. Where an image holds detail at the pixel scale (the aneurism's thin
opaque vessels) no resampling method can match a point-sampled reference, however exact its rays.
This measures that floor with exact rays: `raycast` (pre-integrated, step 0.25) renders the scene
at k times the resolution, and each output pixel is interpolated (Catmull-Rom, as shear-warp's
warp) from the fine rays around it. For even k the output pixel centres lie half-way between
fine rays in both directions, the farthest a resampled pixel can be from its rays, so each column
is the error of a resampler with perfect rays k times as dense as the pixels, in the worst
alignment; `shearwarp` at its default level and at `oversampling` k is measured in the same run.
"""

from __future__ import annotations

import argparse
import datetime
import os
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from benchmarks._cli import int_list, run
from volren.bench.datasets import shared_datasets, shared_folder
from volren.errors import VolrenError
from volren.model import RenderSettings
from volren.renderers.raycast import RaycastRenderer
from volren.testing import image_error
from volren.testing.reference_images import reference_image

#: Catmull-Rom's weights half-way between its two middle taps.
HALF_WAY = np.array([-1.0, 9.0, 9.0, -1.0]) / 16.0


def half_way_downsample(fine: NDArray, k: int) -> NDArray[np.float64]:
    """The (H, W, C) image at the centres of the k-times-coarser pixels, Catmull-Rom interpolated
    from `fine` ((k H, k W, C), k even): coarse pixel i's centre lies at fine index k i + (k - 1) / 2,
    half-way between fine pixels k i + k / 2 - 1 and k i + k / 2. Taps past the border are clamped
    to it, and the result to [0, 1] (the premultiplied range)."""
    if k < 2 or k % 2:
        raise ValueError(f"k must be even and at least 2, got {k}")
    out = np.asarray(fine, dtype=np.float64)
    for axis in (0, 1):
        n = out.shape[axis] // k
        left = k * np.arange(n) + k // 2 - 1
        taps = [np.clip(left + d, 0, out.shape[axis] - 1) for d in (-1, 0, 1, 2)]
        out = sum(w * np.take(out, t, axis=axis) for w, t in zip(HALF_WAY, taps, strict=True))
    return np.clip(out, 0.0, 1.0)


def measure(args: argparse.Namespace) -> int:
    if any(k % 2 for k in args.factors):
        raise VolrenError(
            f"--factors must be even (pixel centres then lie half-way between fine rays), got {args.factors}"
        )
    datasets = shared_datasets(shared_folder(args.shared))
    size = args.size
    lines = [
        f"Measured {datetime.date.today()} by `python -m benchmarks.resampling_floor --datasets "
        f"{','.join(args.datasets)} --styles {','.join(args.styles)} --factors "
        f"{','.join(map(str, args.factors))}`: {size}x{size}, each scene's camera, RMSE against `reference`. "
        "*exact rays*: `raycast`, pre-integrated, step 0.25, one ray per pixel centre; *rays k x, "
        "half-way*: the same rays at k times the resolution, each pixel Catmull-Rom interpolated "
        "half-way between them (a resampler with perfect rays, in the worst alignment); *shearwarp*: "
        "its default level, then `oversampling` k (intermediate pixels per output pixel along each axis).",
        "",
        f"load average at the start: {' '.join(f'{v:.2f}' for v in os.getloadavg())}",
        "",
    ]
    head = ["scene", "exact rays"] + [f"rays {k}x, half-way" for k in args.factors]
    head += ["shearwarp default"] + [f"shearwarp oversampling {k}" for k in args.factors]
    lines += ["| " + " | ".join(head) + " |", "|---|" + "---:|" * (len(head) - 1)]
    from volren_shearwarp import ShearWarpRenderer  # the plugin, as the other plugin benchmarks use it

    for name in args.datasets:
        data = datasets[name]
        volume = data.load()
        camera = data.camera(volume.bounds)
        rays = RaycastRenderer()
        rays.set_volume(volume)
        rays.set_settings(RenderSettings(step=0.25, preintegration=True))
        shear = ShearWarpRenderer()
        shear.set_volume(volume)
        for style, tf in data.transfer_functions():
            if style not in args.styles:
                continue
            ref = reference_image(volume, tf, camera, size, size)
            rays.set_transfer_function(tf)
            shear.set_transfer_function(tf)
            row = [image_error(rays.render(camera, size, size), ref).rmse]
            for k in args.factors:
                row.append(
                    image_error(half_way_downsample(rays.render(camera, k * size, k * size), k), ref).rmse
                )
            shear.set_settings(RenderSettings(step=0.5, preintegration=True))
            row.append(image_error(shear.render(camera, size, size), ref).rmse)
            for k in args.factors:
                shear.set_settings(
                    RenderSettings(step=0.5, preintegration=True, options={"oversampling": float(k)})
                )
                row.append(image_error(shear.render(camera, size, size), ref).rmse)
            line = f"| {name} {style} | " + " | ".join(f"{v:.4f}" for v in row) + " |"
            print(line, flush=True)
            lines.append(line)
        rays.release()
        shear.release()
    lines += ["", f"load average at the end: {' '.join(f'{v:.2f}' for v in os.getloadavg())}"]
    text = "\n".join(lines) + "\n"
    if args.out:
        Path(args.out).mkdir(parents=True, exist_ok=True)
        (Path(args.out) / "resampling_floor.md").write_text(text)
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.resampling_floor", description=__doc__.split("\n")[0]
    )
    parser.add_argument("--shared", help="the folder with data/ and scenes/ (default: $VOLREN_SHARED)")
    parser.add_argument(
        "--datasets", type=lambda s: s.split(","), default=["bonsai", "engine", "aneurism", "ironProt"]
    )
    parser.add_argument("--styles", type=lambda s: s.split(","), default=["smooth", "opaque"])
    parser.add_argument(
        "--factors", type=int_list(2), default=[2, 4], help="even oversampling factors (default 2,4)"
    )
    parser.add_argument("--size", type=int, default=512, help="output pixels along each axis (default 512)")
    parser.add_argument("--out", help="folder to write resampling_floor.md into (BENCHMARKS.md's section)")
    return run(measure, parser, argv)


if __name__ == "__main__":
    raise SystemExit(main())
