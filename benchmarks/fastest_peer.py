"""`python -m benchmarks.fastest_peer`: a render with no options against VTK's fastest mapper that
reaches its error, frames interleaved.

Why: `benchmarks.defaults_ab` compares with VTK's default (the smart mapper, which on a machine
without a GPU runs its GPU ray caster in software); a CPU user would pick VTK's fastest: on grids
the fixed-point ray caster or the GPU ray caster on llvmpipe, each at its own step, on meshes the
unstructured ray caster or projected tetrahedra. Per scene, every such VTK setting draws the scene's
view once and is scored against `reference`; of those with an RMSE at most ours, the one whose
frame was quickest is timed against `auto`'s choice, one frame each in turn while the camera turns
2 degrees a pair. Where no VTK setting reaches our error, the most accurate one is timed and the
row says so; the last column is VTK's quickest setting at any error (its one scored frame), the
bound below which no VTK setting goes.

    python -m benchmarks.fastest_peer [--shared DIR] [--datasets a,b] [--frames N] [--size S] [--out FILE]
"""

from __future__ import annotations

import argparse
import datetime
import statistics
from contextlib import ExitStack

from benchmarks.scene_table import ms_text, no_options_choice, scene_table, table_main, timed_frame
from volren.api import prepared_renderer
from volren.bench.datasets import Dataset
from volren.bench.sweep import Config
from volren.errors import VolrenError
from volren.renderers.base import render_frame
from volren.testing import image_error
from volren.testing.reference_images import reference_image

TURN = 2.0  # degrees of azimuth between frame pairs, as `volren bench run` turns
STEPS = (2.0, 1.0, 0.5, 0.25)
#: VTK's settings a CPU user could pick, by volume kind.
PEERS: dict[str, tuple[Config, ...]] = {
    "uniform": (
        *(Config("vtk-fixed_point", step) for step in STEPS),
        *(Config("vtk-gpu", step, jitter=False) for step in STEPS),
    ),  # fmt: skip
    "tet": (Config("vtk-raycast", preintegration=False), Config("vtk-projected")),
}


def _peer_errors(d: Dataset, volume, tf, camera, truth, size: int) -> list[tuple[Config, float, float]]:
    """(config, RMSE, ms of its first warm frame) of every VTK setting of this kind that draws here."""
    found = []
    for config in PEERS[d.kind]:
        try:
            with prepared_renderer(config.renderer, volume, tf, config.settings()) as renderer:
                render_frame(renderer, camera, size, size)  # warm-up: shaders, uploads
                ms, image = timed_frame(renderer, camera, size)
        except VolrenError:
            continue
        found.append((config, image_error(image, truth).rmse, ms))
    return found


def scene_row(d: Dataset, volume, style: str, tf, size: int, frames: int) -> str:
    camera_at = lambda turn: d.camera(volume.bounds, turn=turn)  # noqa: E731
    name, settings = no_options_choice(volume, tf, camera_at(0.0))
    truth = reference_image(volume, tf, camera_at(0.0), size, size)
    with prepared_renderer(name, volume, tf, settings) as ours:
        our_rmse = image_error(render_frame(ours, camera_at(0.0), size, size)[0], truth).rmse
    peers = _peer_errors(d, volume, tf, camera_at(0.0), truth, size)
    reaching = [p for p in peers if p[1] <= our_rmse]
    reached = bool(reaching)
    config, peer_rmse, _ = min(reaching, key=lambda p: p[2]) if reached else min(peers, key=lambda p: p[1])
    with ExitStack() as stack:
        ours = stack.enter_context(prepared_renderer(name, volume, tf, settings))
        vtk = stack.enter_context(prepared_renderer(config.renderer, volume, tf, config.settings()))
        for renderer in (ours, vtk):
            render_frame(renderer, camera_at(0.0), size, size)
        ms: tuple[list[float], list[float]] = ([], [])
        for f in range(frames):
            camera = camera_at(TURN * (f + 1))
            for which in (0, 1) if f % 2 == 0 else (1, 0):
                ms[which].append(timed_frame((ours, vtk)[which], camera, size)[0])
    ours_ms, vtk_ms = statistics.median(ms[0]), statistics.median(ms[1])
    peer = f"{config.curve.removeprefix('vtk-')} {config.label}" + ("" if reached else " (its most accurate: "
                                                                       "none reaches ours)")  # fmt: skip
    quick, quick_rmse, quick_ms = min(peers, key=lambda p: p[2])
    quickest = (
        f"{quick.curve.removeprefix('vtk-')} {quick.label}: {ms_text(quick_ms)} ms, RMSE {quick_rmse:.3g}"
    )
    return (f"| {d.name}/{style} | {name} | {ms_text(ours_ms)} | {our_rmse:.3g} | {peer} | {ms_text(vtk_ms)} | "
            f"{peer_rmse:.3g} | {vtk_ms / ours_ms:.2f}x | {quickest} |")  # fmt: skip


def measure(args: argparse.Namespace) -> int:
    intro = (f"Measured {datetime.date.today()} by `python -m benchmarks.fastest_peer --shared ../shared --frames "
             f"{args.frames}{' --datasets ' + args.datasets if args.datasets else ''}`: {args.size}x{args.size}; per "
             "scene `auto`'s choice with no options against the quickest VTK setting whose RMSE against `reference` "
             f"is at most ours, the median of {args.frames} turning frames of each, interleaved.")  # fmt: skip
    header = ("| scene | ours | ours ms | our RMSE | VTK's fastest at our error | its ms | its RMSE | its ms / ours "
              "| VTK's quickest at any error (one frame) |", "|---|---|---:|---:|---|---:|---:|---:|---|")  # fmt: skip
    return scene_table(args, intro, header, scene_row)


def main(argv: list[str] | None = None) -> int:
    return table_main("fastest_peer", __doc__, 5, measure, argv)


if __name__ == "__main__":
    raise SystemExit(main())
