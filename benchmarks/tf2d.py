"""2D transfer functions (value x gradient magnitude) against `reference`, and what a frame costs
(python -m benchmarks.tf2d). For each grid scene (the hard procedural ones, and the shared ones with
--shared) two 2D TFs are drawn: `from 1D`, the scene's 1D TF as one band over every gradient (what
the editor makes when a user switches to 2D: `seeded_2d`), and `boundary`, the same band kept only
above a third of the largest gradient (Kniss et al. 2002: the TF that brings out boundaries), and
`blob`, `from 1D` with a Gaussian widget over it (the app's 2D widget gesture, `volren bench app`). Every
renderer that draws 2D TFs draws them at its `default` quality level and, for `raycast`, at fixed
steps (the 2D march has no error-targeted step search), each image compared with `reference`'s
(cached: `volren.testing.reference_images`). Frame times are medians of `--frames` warm frames.
The table decides what `auto` picks for a 2D TF: the fastest renderer whose RMSE is within that of
the others' on every scene."""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np

from volren.api import prepared_renderer
from volren.app.core.tf_seeding import seeded_2d
from volren.bench.datasets import SCENES, hard_datasets, scene_inputs, shared_folder
from volren.model.camera import Camera
from volren.model.scene_class import SceneClass
from volren.model.settings import RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TFWidget, TransferFunction2D
from volren.model.volume import UniformVolume
from volren.quality import at_level
from volren.renderers.raycast.march_inputs import gradients
from volren.renderers.registry import registry
from volren.testing.metrics import image_error
from volren.testing.reference_images import reference_image

#: The shared grid scene measured with --shared (dataset, TF style). One: `reference` takes minutes
#: per 2D image of a 256^3 grid (engine's spiky TF, bonsai's spiky with a blob: over 7 min at 256^2).
SHARED = (("bonsai", "smooth"),)
#: raycast's fixed steps measured beside its level (in units of the volume's characteristic length).
RAYCAST_STEPS = (0.5, 0.25)


def largest_gradient(volume: UniformVolume) -> float:
    """The largest gradient magnitude at the grid points (the reference's central differences)."""
    g = gradients(np.asarray(volume.values), volume.spacing)
    return float(np.sqrt((g.values.astype(np.float64) ** 2).sum(-1)).max() * g.unit) or 1.0


def two_d_tfs(tf: TransferFunction1D, volume: UniformVolume) -> dict[str, TransferFunction2D]:
    """`from 1D`, `boundary` and `blob` (see the module's docstring) for a scene's 1D TF."""
    lo, hi = volume.value_range
    gmax = largest_gradient(volume)
    seeded = seeded_2d(tf, (lo, hi), gmax)
    band = seeded.widgets[0]
    boundary = TFWidget.from_1d(TransferFunction1D(band.color_points, band.opacity_points), (gmax / 3, gmax))
    blob = TFWidget.gaussian(
        (lo + 0.5 * (hi - lo), 0.5 * gmax), (0.08 * (hi - lo), 0.3 * gmax), (1.0, 0.6, 0.2), 0.5
    )
    return {
        "from 1D": seeded,
        "boundary": TransferFunction2D((lo, hi), (0.0, gmax), [boundary], tf.opacity_unit_distance),
        "blob": TransferFunction2D((lo, hi), (0.0, gmax), [band, blob], tf.opacity_unit_distance),
    }


def timed(renderer, camera: Camera, size: int, frames: int) -> tuple[float, np.ndarray]:
    image = renderer.render(camera, size, size)
    times = []
    for _ in range(frames):
        start = time.perf_counter()
        image = renderer.render(camera, size, size)
        times.append(1000.0 * (time.perf_counter() - start))
    return statistics.median(times), image


def scenes(shared) -> list[tuple[str, UniformVolume, TransferFunction1D, Camera]]:
    out = []
    for name, dataset in hard_datasets().items():
        if dataset.kind != "uniform":
            continue
        volume = dataset.load()
        for _, tf in dataset.transfer_functions():
            out.append((name, volume, tf, dataset.camera(volume.bounds)))
    if shared is not None:
        for name, style in SHARED:
            _, _, az, el, zoom = SCENES[name]
            volume, tf = scene_inputs(shared, name, style)
            out.append((f"{name}/{style}", volume, tf, Camera.orbit(volume.bounds, az, el, zoom)))
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument(
        "--shared", help="the folder with data/ and scenes/ (default: $VOLREN_SHARED; none: hard scenes only)"
    )
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--frames", type=int, default=3)
    args = parser.parse_args(argv)
    shared = shared_folder(args.shared, required=False)
    command = " ".join(["python -m benchmarks.tf2d", *(argv if argv is not None else sys.argv[1:])])
    print(f"From `{command}`: {args.size}x{args.size}, medians of {args.frames} warm frames; "
          f"load average at the start {' '.join(f'{v:.2f}' for v in os.getloadavg())}.")  # fmt: skip
    print()
    print("| scene | 2D TF | renderer | settings | RMSE | ms |")
    print("|---|---|---|---|---:|---:|")
    names = [n for n in registry.names() if n != "reference"]
    for scene, volume, tf1, camera in scenes(shared):
        for label, tf in two_d_tfs(tf1, volume).items():
            kind = SceneClass.of(volume, tf)  # a 2D TF has no TF class: the volume kind's levels
            reference = reference_image(volume, tf, camera, args.size, args.size)
            runs: list[tuple[str, str, RenderSettings]] = []
            for name in names:
                support = registry.capabilities(name).kinds.get("uniform")
                if support is None or 2 not in support.tf_dims:
                    continue
                base = at_level(name, kind, "default", RenderSettings()) or RenderSettings()
                runs.append((name, "default level", base))
                if name == "raycast":
                    runs += [(name, f"step {s}", RenderSettings(step=s)) for s in RAYCAST_STEPS]
            for name, shown, settings in runs:
                with prepared_renderer(name, volume, tf, settings) as renderer:
                    ms, image = timed(renderer, camera, args.size, args.frames)
                rmse = image_error(image, reference).rmse
                print(f"| {scene} | {label} | {name} | {shown} | {rmse:.5f} | {ms:.1f} |", flush=True)
    print()
    print(f"Load average at the end {' '.join(f'{v:.2f}' for v in os.getloadavg())}.")


if __name__ == "__main__":
    main()
