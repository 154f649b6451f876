"""`python -m benchmarks.defaults_ab`: a render with no options against VTK's default, frames interleaved.

Why: the fast-defaults goal is about what `volren render` gives with no options (`auto` at quality
`default`) against VTK's default (vtkSmartVolumeMapper on grids, the unstructured ray caster on
meshes: the peer of `benchmarks.quality_levels`) on every shared scene: at no more error, >= 3x faster
on grids and >= 10x on meshes. `benchmarks.quality_levels` reads both frame times from sweeps taken
minutes apart, and this machine's frame times drift by 20-40 % between runs; here each scene's two
renderers draw alternately, one frame each with the camera turning 2 degrees between pairs (which
of the two goes first alternates too), so both see the same load.

    python -m benchmarks.defaults_ab [--shared DIR] [--datasets a,b] [--frames N] [--size S] [--out FILE]

Prints a markdown table: per scene `auto`'s choice, both medians, VTK's over ours, and both RMSEs
against `reference` (cached as `volren.testing.reference_images` does) with their ratio.
"""

from __future__ import annotations

import argparse
import datetime
import statistics
from contextlib import ExitStack

from benchmarks.quality_levels import VTK_DEFAULT, _configs
from benchmarks.scene_table import ms_text, no_options_choice, scene_table, table_main, timed_frame
from volren.api import prepared_renderer
from volren.bench.datasets import Dataset
from volren.renderers.base import render_frame
from volren.testing import image_error
from volren.testing.reference_images import reference_image

TURN = 2.0  # degrees of azimuth between frame pairs, as `volren bench run` turns


def scene_row(d: Dataset, volume, style: str, tf, size: int, frames: int) -> str:
    """One scene: both renderers prepared, a warm-up frame each at the scene's view (scored against
    the reference), then `frames` pairs of turning frames."""
    camera_at = lambda turn: d.camera(volume.bounds, turn=turn)  # noqa: E731
    name, settings = no_options_choice(volume, tf, camera_at(0.0))
    curve, label = VTK_DEFAULT[d.kind]
    peer = _configs(d.kind, {curve})[(curve, label)]
    truth = reference_image(volume, tf, camera_at(0.0), size, size)
    with ExitStack() as stack:
        ours = stack.enter_context(prepared_renderer(name, volume, tf, settings))
        vtk = stack.enter_context(prepared_renderer(peer.renderer, volume, tf, peer.settings()))
        errors = [
            image_error(render_frame(r, camera_at(0.0), size, size)[0], truth).rmse for r in (ours, vtk)
        ]
        ms: tuple[list[float], list[float]] = ([], [])
        for f in range(frames):
            camera = camera_at(TURN * (f + 1))
            order = (0, 1) if f % 2 == 0 else (1, 0)
            for which in order:
                ms[which].append(timed_frame((ours, vtk)[which], camera, size)[0])
    ours_ms, vtk_ms = statistics.median(ms[0]), statistics.median(ms[1])
    chosen = f"{name}: {settings.step:g} step{', pre-integrated' if settings.preintegration else ''}"
    if settings.options:
        chosen += ", " + ", ".join(f"{k} {v}" for k, v in sorted(settings.options.items()))
    return (f"| {d.name}/{style} | {chosen} | {ms_text(ours_ms)} | {ms_text(vtk_ms)} | {vtk_ms / ours_ms:.1f}x "
            f"| {errors[0]:.3g} | {errors[1]:.3g} | {errors[0] / errors[1]:.2f} |")  # fmt: skip


def measure(args: argparse.Namespace) -> int:
    intro = (f"Measured {datetime.date.today()} by `python -m benchmarks.defaults_ab --shared ../shared --frames "
             f"{args.frames}`: {args.size}x{args.size}, per scene the median of {args.frames} turning frames of each "
             "renderer, the two renderers' frames interleaved; RMSE at the scene's view against `reference`.")  # fmt: skip
    header = ("| scene | auto's choice (no options) | ours ms | VTK's default ms | VTK / ours | our RMSE "
              "| VTK's RMSE | ours / VTK's |", "|---|---|---:|---:|---:|---:|---:|---:|")  # fmt: skip
    return scene_table(args, intro, header, scene_row)


def main(argv: list[str] | None = None) -> int:
    return table_main("defaults_ab", __doc__, 7, measure, argv)


if __name__ == "__main__":
    raise SystemExit(main())
