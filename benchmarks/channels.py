"""`python -m benchmarks.channels --shared ../shared`: what mixing a volume's channels costs and how
accurate it is, on the shared multi-component volumes (a T1/T2/FLAIR brain MRI, VTK's vase with
four identical components) and a procedural two-channel field.

Why: several channels mixed in one optical model (`volren.model.channels`: their extinctions and
emissions add) cost a lookup per channel and sample; this measures that cost against the first
channel drawn alone, and checks the mix where it has an exact answer: four identical channels at
weight 1/4 each are the one channel (the vase). Per scene, with the renderer and settings a
render with no options picks (`auto`, quality `default`, pre-integration off for channels): the
first channel alone with its TF, every channel mixed (each its default ramp over its range, in its
colour), and the mix with all channels but the first hidden, at the step the mix's error target
chose, warm, median of `--frames` turning frames each, in turns; then the error of the first two,
each at the settings a render with no options has, against `reference` at `--error-size`.
"""

from __future__ import annotations

import argparse
import os
import statistics
from collections.abc import Iterator
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks._cli import run
from benchmarks.scene_table import ms_text, named_scene_table, parser, timed_frame
from volren.bench.datasets import shared_folder

FRAMES = 5


def _stacked(path: Path, array: str, count: int) -> Any:
    """The volume at `path` with its array's `count` components as channels (the first as values)."""
    from volren.io import load_volume
    from volren.model import UniformVolume
    from volren.model.channels import ChannelSet

    parts = [load_volume(path, scalars=f"{array}:{c}") for c in range(count)]
    stack = np.stack([p.values for p in parts])
    first = parts[0]
    return UniformVolume(stack[0], first.spacing, first.origin, name=path.stem,
                         channels=ChannelSet(stack, names=tuple(f"{array}:{c}" for c in range(count))))  # fmt: skip


def _scenes(shared: Path | None) -> Iterator[tuple[str, Any, Any]]:
    """(name, volume with channels, channel TF) per scene."""
    from volren.model import UniformVolume
    from volren.model.channels import ChannelSet, ChannelTransferFunction

    if shared is not None and (shared / "data" / "multichannel").is_dir():
        folder = shared / "data" / "multichannel"
        stroke = _stacked(folder / "stroke_t1_t2_flair.vti", "T1_T2_FLAIR", 3)
        yield "stroke/T1+T2+FLAIR", stroke, ChannelTransferFunction.for_channels(stroke.channels)
        vase = _stacked(folder / "vase_4comp.vti", "Scalars_", 4)
        ramp = ChannelTransferFunction.for_channels(vase.channels).tfs[0]
        yield "vase/4 x 1/4", vase, ChannelTransferFunction([ramp] * 4, weights=[0.25] * 4)
    n = 96
    z, y, x = np.mgrid[0:n, 0:n, 0:n].astype(np.float32)
    a = np.exp(-(((x - n / 3) ** 2 + (y - n / 2) ** 2 + (z - n / 2) ** 2) / (n / 4) ** 2))
    b = np.exp(-(((x - 2 * n / 3) ** 2 + (y - n / 2) ** 2 + (z - n / 2) ** 2) / (n / 4) ** 2))
    stack = np.stack([a, b]).astype(np.float32)
    volume = UniformVolume(stack[0], name="two blobs", channels=ChannelSet(stack))
    yield "blobs/2 channels", volume, ChannelTransferFunction.for_channels(volume.channels)


def _row(name: str, volume: Any, mixed: Any, size: int, frames: int, error_size: int) -> str:
    from dataclasses import replace

    from volren.api import prepared_renderer
    from volren.model import Camera, RenderSettings
    from volren.model.channels import ChannelTransferFunction
    from volren.model.scene_class import SceneClass
    from volren.quality import resolve
    from volren.testing.metrics import image_error
    from volren.testing.reference_images import reference_image

    first = mixed.tfs[0]
    alone = ChannelTransferFunction(mixed.tfs, mixed.weights, [True] + [False] * (mixed.count - 1))

    def view(turn: float) -> Any:
        return Camera.orbit(volume.bounds, 30.0 + turn, 20.0)

    renderer_name, settings, _ = resolve(SceneClass.of(volume, first), 1, "auto", "default", RenderSettings(),
                                         cameras=(view(0.0),), bounds=volume.bounds, channels=True)  # fmt: skip
    tfs = {"plain": first, "mixed": mixed, "alone": alone}  # plain: the first channel, the volume's values
    times: dict[str, list[float]] = {key: [] for key in tfs}
    edited: dict[str, list[float]] = {key: [] for key in tfs}
    images = {}
    errors = {}
    with prepared_renderer(renderer_name, volume, first, settings) as renderer:
        camera = view(0.0)
        for key in ("plain", "mixed"):  # at the settings a render with no options has (its step search too)
            renderer.set_transfer_function(tfs[key])
            image = renderer.render(camera, error_size, error_size)
            truth = reference_image(
                volume, tfs[key], camera, error_size, error_size, replace(settings, options={})
            )
            errors[key] = image_error(image, truth).rmse
        renderer.set_transfer_function(mixed)
        renderer.render(camera, size, size)
        step = renderer.last_frame.counters.get("step", settings.step)
        # the three TFs timed at one step, the one the mix's search chose: the cost of mixing
        renderer.set_settings(settings.with_(step=step, options={**settings.options, "target_error": 0.0}))
        for tf in tfs.values():  # warm: tables, bricks
            renderer.set_transfer_function(tf)
            timed_frame(renderer, camera, size)
        for k in range(
            frames
        ):  # in turns: the frame after the TF changed (tables, bricks rebuilt), then the next
            for key, tf in tfs.items():
                renderer.set_transfer_function(tf)
                ms, _ = timed_frame(renderer, view(2.0 * k + 0.5), size)
                edited[key].append(ms)
                ms, images[key] = timed_frame(renderer, view(2.0 * (k + 1)), size)
                times[key].append(ms)
    ms = {key: statistics.median(values) for key, values in times.items()}
    after = {key: statistics.median(values) for key, values in edited.items()}
    alike = (
        float(np.abs(images["mixed"] - images["plain"]).max()) if name.startswith("vase") else float("nan")
    )
    return (f"| {name} | {mixed.count} | {renderer_name} {step:.3g} | {ms_text(ms['plain'])} | "
            f"{ms_text(ms['mixed'])} | {ms['mixed'] / ms['plain']:.2f} | {ms_text(ms['alone'])} | "
            f"{ms['alone'] / ms['plain']:.2f} | {errors['plain']:.4f} | {errors['mixed']:.4f} | "
            f"{'-' if alike != alike else f'{alike:.1e}'} | {ms_text(after['mixed'])} |")  # fmt: skip


def measure(args: argparse.Namespace) -> int:
    shared = shared_folder(args.shared, required=False)
    intro = (f"Measured by `python -m benchmarks.channels --shared ../shared --size {args.size} --frames "
             f"{args.frames}`: {args.size}x{args.size}, the renderer and settings a render with no options picks "
             f"for the multi-channel scene, at the step its error target chose for the mix (*step*, in voxels), "
             f"warm, median of {args.frames} turning frames each, the three TFs in turns (each frame timed is the "
             f"second after its TF was set: *after an edit* is the first, which rebuilds the tables and bricks); "
             f"{os.cpu_count()} cores. "
             f"*first alone*: the first channel's TF without the others; *mixed*: every channel; *mixed, one "
             f"shown*: the others hidden. RMSE against `reference` at {args.error_size}x{args.error_size}, each at "
             f"the settings a render with no options has. *mixed vs alone*: the vase's four identical channels at "
             f"weight 1/4 against the one channel (the same image up to float rounding).")  # fmt: skip
    header = ("| scene | channels | renderer, step | first alone ms | mixed ms | mixed / alone | mixed, one shown ms "
             "| one shown / alone | RMSE alone | RMSE mixed | mixed vs alone | mixed after an edit ms |",
             "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")  # fmt: skip
    rows = ((name, partial(_row, name, volume, tf, args.size, args.frames, args.error_size))
            for name, volume, tf in _scenes(shared))  # fmt: skip
    return named_scene_table(args, intro, header, rows)


def main(argv: list[str] | None = None) -> int:
    cli = parser(
        "python -m benchmarks.channels", (__doc__ or "").split("\n")[0], FRAMES, "docs/bench/channels.md"
    )
    cli.add_argument(
        "--error-size", type=int, default=128, help="image side of the error columns (default 128)"
    )
    return run(measure, cli, argv)


if __name__ == "__main__":
    raise SystemExit(main())
