"""`python -m benchmarks.viewer_peers`: a render with no options against what a PyVista or a napari
user gets today, frames interleaved.

Why: `benchmarks.fastest_peer` compares with VTK's fastest mapper, which a user picks only after
learning VTK; most users see a volume through PyVista's ``Plotter.add_volume`` or napari's 3D view
(vispy's Volume visual). `volren.bench.viewer_peers` draws our scene the way each does (the TF's
colours and opacity handed over as such users would, everything else left at the tool's default;
on llvmpipe here). Per uniform scene of the shared datasets and the bundled samples: `auto`'s
choice with no options (as `volren render` picks it) and each peer, scored against `reference` at
the scene's view, then timed one frame each in turn (the order rotating) while the camera turns 2
degrees a frame; the medians of --frames. A peer's one-shot cost is its plotter or canvas, the
grid's upload and its first frame (the packages already imported). A peer that cannot draw here
says why in its cells.

    python -m benchmarks.viewer_peers [--shared DIR] [--datasets a,b] [--frames N] [--size S] [--out FILE]
"""

from __future__ import annotations

import argparse
import datetime
import statistics
import time
from contextlib import ExitStack

from benchmarks.scene_table import ms_text, no_options_choice, scene_table, table_main, timed_frame
from volren.api import prepared_renderer
from volren.bench.datasets import Dataset
from volren.bench.viewer_peers import VIEWER_PEERS, open_peer
from volren.renderers.base import render_frame
from volren.testing import image_error
from volren.testing.reference_images import reference_image

TURN = 2.0  # degrees of azimuth between frames, as `volren bench run` turns
#: The cells of a peer that did not draw: ms, RMSE, ratio, one-shot.
PEER_CELLS = 4


def _preload() -> None:
    """Import what the peers import, so that no one-shot cost holds an import."""
    for module in ("pyvista", "matplotlib.colors", "vispy.scene"):
        try:
            __import__(module)
        except ImportError:
            pass  # the peer's first frame says what is missing


def _open(stack: ExitStack, name: str, volume, tf, camera, truth, size: int):
    """(peer, one-shot ms, RMSE at the scene's view), or (None, why, None) where it cannot draw."""
    try:
        start = time.perf_counter()
        peer = stack.enter_context(open_peer(name, volume, tf))
        image, _ = render_frame(peer, camera, size, size)
        first = (time.perf_counter() - start) * 1000.0
    except Exception as exc:  # a peer's failure is a cell of the table, never the end of the run
        return None, f"{type(exc).__name__}: {str(exc).splitlines()[0][:120] if str(exc) else ''}", None
    return peer, first, image_error(image, truth).rmse


def scene_row(d: Dataset, volume, style: str, tf, size: int, frames: int) -> str:
    camera_at = lambda turn: d.camera(volume.bounds, turn=turn)  # noqa: E731
    name, settings = no_options_choice(volume, tf, camera_at(0.0))
    truth = reference_image(volume, tf, camera_at(0.0), size, size)
    with ExitStack() as stack:
        ours = stack.enter_context(prepared_renderer(name, volume, tf, settings))
        our_rmse = image_error(render_frame(ours, camera_at(0.0), size, size)[0], truth).rmse
        opened = {p: _open(stack, p, volume, tf, camera_at(0.0), truth, size) for p in VIEWER_PEERS}
        drawers = [("ours", ours)] + [(p, peer) for p, (peer, _, _) in opened.items() if peer is not None]
        ms: dict[str, list[float]] = {who: [] for who, _ in drawers}
        for f in range(frames):
            camera = camera_at(TURN * (f + 1))
            k = f % len(drawers)
            for who, drawer in drawers[k:] + drawers[:k]:
                ms[who].append(timed_frame(drawer, camera, size)[0])
    ours_ms = statistics.median(ms["ours"])
    cells = [d.name + "/" + style, name, ms_text(ours_ms), f"{our_rmse:.3g}"]
    for p, (peer, first, rmse) in opened.items():
        if peer is None:
            cells += [f"cannot draw: {first}"] + ["-"] * (PEER_CELLS - 1)
            continue
        peer_ms = statistics.median(ms[p])
        cells += [ms_text(peer_ms), f"{rmse:.3g}", f"{peer_ms / ours_ms:.2f}x", ms_text(first)]
    return "| " + " | ".join(cells) + " |"


def measure(args: argparse.Namespace) -> int:
    _preload()
    intro = (f"Measured {datetime.date.today()} by `python -m benchmarks.viewer_peers --shared ../shared --frames "
             f"{args.frames}{' --datasets ' + args.datasets if args.datasets else ''}`: {args.size}x{args.size}; per "
             "uniform scene `auto`'s choice with no options against `pyvista.Plotter.add_volume` and vispy's Volume "
             "visual as napari draws it (`volren.bench.viewer_peers`: the TF handed over as their users would, the "
             "rest at the tools' defaults, on llvmpipe), each scored against `reference` and timed as the median of "
             f"{args.frames} turning frames, interleaved; one-shot: plotter or canvas, upload and first frame.")  # fmt: skip
    peers = " | ".join(f"{p} ms | its RMSE | its ms / ours | {p} one-shot ms" for p in VIEWER_PEERS)
    header = (f"| scene | ours | ours ms | our RMSE | {peers} |",
              "|---|---|---:|---:|" + "---:|---:|---:|---:|" * len(VIEWER_PEERS))  # fmt: skip
    return scene_table(args, intro, header, scene_row, kinds=("uniform",))


def main(argv: list[str] | None = None) -> int:
    return table_main("viewer_peers", __doc__, 5, measure, argv)


if __name__ == "__main__":
    raise SystemExit(main())
