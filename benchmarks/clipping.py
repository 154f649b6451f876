"""Clipped frames against `reference`, and what clipping costs (python -m benchmarks.clipping).

For each shared scene (dataset x TF style), every registered renderer that declares `clip_region`
for its volume kind draws the scene at its `default` quality level uncut, cut by one oblique
plane (through the centre, keeping the far side of (1, 0.6, -0.4)) and by three (each taking a
corner off). Each image is compared with `reference` drawn with the same clip region (cached:
`volren.testing.reference_images`). Frame times are medians of `--frames` frames after a warm-up,
the uncut and the cut frames interleaved in one process so that load falls on both alike.

The printed table holds, per renderer and scene: the RMSE uncut, with one plane and with three,
and the time of the clipped frames over the uncut one. The targets (clipping issue): a clipped
RMSE at most the uncut RMSE, a clipped frame no dearer than the uncut one.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time

import numpy as np

from volren.api import prepared_renderer
from volren.bench.datasets import SCENES, STYLES, shared_folder
from volren.model.camera import Camera
from volren.model.clip_region import ClipPlane, ClipRegion
from volren.model.scene_class import SceneClass
from volren.model.settings import RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import Volume
from volren.quality import at_level
from volren.renderers.registry import registry
from volren.testing.metrics import image_error
from volren.testing.reference_images import reference_image


def clip_regions(volume: Volume) -> dict[str, ClipRegion]:
    """The cuts measured, placed by the volume's bounds: none, one plane, three planes."""
    lo = np.asarray(volume.bounds[0::2], dtype=np.float64)
    span = np.asarray(volume.bounds[1::2], dtype=np.float64) - lo

    def at(*fractions: float) -> tuple[float, float, float]:
        return tuple(float(v) for v in lo + span * np.asarray(fractions))  # type: ignore[return-value]

    one = (ClipPlane(at(0.5, 0.5, 0.5), (1.0, 0.6, -0.4)),)
    three = (
        ClipPlane(at(0.3, 0.5, 0.5), (1.0, 0.2, 0.1)),
        ClipPlane(at(0.5, 0.75, 0.5), (-0.2, -1.0, 0.3)),
        ClipPlane(at(0.5, 0.5, 0.7), (0.1, 0.3, -1.0)),
    )
    return {"none": ClipRegion(), "1 plane": ClipRegion(one), "3 planes": ClipRegion(three)}


def interleaved_ms(renderer, settings: dict[str, RenderSettings], camera: Camera, size: int,
                   frames: int) -> tuple[dict[str, float], dict[str, np.ndarray]]:  # fmt: skip
    """Median ms per frame and the last image of each settings, frames of all interleaved."""
    times: dict[str, list[float]] = {name: [] for name in settings}
    images: dict[str, np.ndarray] = {}
    for s in settings.values():  # warm-up: tables, compilation
        renderer.set_settings(s)
        renderer.render(camera, size, size)
    for _ in range(frames):
        for name, s in settings.items():
            renderer.set_settings(s)
            start = time.perf_counter()
            images[name] = renderer.render(camera, size, size)
            times[name].append((time.perf_counter() - start) * 1000.0)
    return {name: statistics.median(t) for name, t in times.items()}, images


def main(argv: list[str] | None = None) -> None:
    from volren.io import load_volume

    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--shared", help="the folder with data/ and scenes/ (default: $VOLREN_SHARED)")
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--datasets", default=",".join(SCENES))
    parser.add_argument("--styles", default=",".join(STYLES))
    parser.add_argument("--renderers", default="", help="comma-separated (default: every one that clips)")
    parser.add_argument("--frames", type=int, default=3)
    parser.add_argument("--option", action="append", default=[], metavar="KEY=VALUE",
                        help="a renderer option over its level's (repeatable; e.g. oversampling=6)")  # fmt: skip
    args = parser.parse_args(argv)
    extra = {key: json.loads(value) for key, _, value in (o.partition("=") for o in args.option)}
    shared = shared_folder(args.shared)
    size = args.size
    command = " ".join(["python -m benchmarks.clipping", *(argv if argv is not None else sys.argv[1:])])
    print(f"From `{command}`: {size}x{size}, medians of {args.frames} frames, each renderer at its `default` "
          f"quality level; load average at the start {' '.join(f'{v:.2f}' for v in os.getloadavg())}.")  # fmt: skip
    print()
    print(
        "| dataset | TF | renderer | RMSE uncut | RMSE 1 plane | RMSE 3 planes | ms uncut | 1 plane / uncut | 3 planes / uncut |"
    )
    print("|---|---|---|---:|---:|---:|---:|---:|---:|")
    wanted = [n for n in args.renderers.split(",") if n]
    for dataset in args.datasets.split(","):
        path, scalars, az, el, zoom = SCENES[dataset]
        volume = load_volume(shared / "data" / path, scalars=scalars)
        camera = Camera.orbit(volume.bounds, az, el, zoom)
        regions = clip_regions(volume)
        for style in args.styles.split(","):
            tf = TransferFunction1D.from_dict(
                json.loads((shared / "scenes" / f"{dataset}-{style}.json").read_text())
            )
            kind = SceneClass.of(volume, tf)
            references = {
                name: reference_image(volume, tf, camera, size, size, RenderSettings(clip=region))
                for name, region in regions.items()
            }
            for name in wanted or registry.names():
                support = registry.capabilities(name).kinds.get(volume.kind)
                if name == "reference" or support is None or not support.clip_region:
                    continue
                base = at_level(name, kind, "default", RenderSettings()) or RenderSettings()
                if extra:
                    base = base.with_(options={**base.options, **extra})
                settings = {cut: base.with_(clip=region) for cut, region in regions.items()}
                with prepared_renderer(name, volume, tf, base) as renderer:
                    ms, images = interleaved_ms(renderer, settings, camera, size, args.frames)
                rmse = {cut: image_error(images[cut], references[cut]).rmse for cut in regions}
                print(f"| {dataset} | {style} | {name} | {rmse['none']:.5f} | {rmse['1 plane']:.5f} | "
                      f"{rmse['3 planes']:.5f} | {ms['none']:.1f} | {ms['1 plane'] / ms['none']:.2f} | "
                      f"{ms['3 planes'] / ms['none']:.2f} |", flush=True)  # fmt: skip
    print()
    print(f"Load average at the end {' '.join(f'{v:.2f}' for v in os.getloadavg())}.")


if __name__ == "__main__":
    main()
