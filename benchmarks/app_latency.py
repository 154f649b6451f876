"""`python -m benchmarks.app_latency`: how responsive the desktop app is: TF edit to new frame, and frames per second while rotating.

Runs the real `MainWindow` (offscreen when there is no display) with its render thread, frame
scheduler and viewport, drives it the way a person does, and times what they see:

- **TF edit latency:** an opacity point moves (one finished edit, like a click in the 1D editor);
  the clock stops when the full-quality frame for that edit has been handed to the viewport.
- **TF drag:** the same point moves continuously for a while inside an interaction (a drag in the
  editor); counts the preview frames shown per second.
- **Rotation:** the camera turns by 2 degrees every 16 ms (a 60 Hz mouse) for a while; counts the
  frames shown per second, and the time from releasing the mouse to the full-quality frame.

Frames are counted when the window shows them (`MainWindow.frameShown`), after the conversion to
8-bit pixels; the repaint itself (a QImage blit) is not part of the clock.

- **Joint histogram:** the 2D TF editor's value x gradient-magnitude histogram of a 256^3 uint8
  volume, computed in full (no subsampling up to `MAX_SAMPLES` points); the app's target is well
  under `HISTOGRAM_TARGET_S` (the tests check what it computes, this measures how fast).
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from benchmarks._cli import run
from volren.app.timing.drive import application, drive_at_60hz, wait
from volren.bench.datasets import SCENES, scene_inputs, shared_folder
from volren.errors import VolrenError

COMMAND = "python -m benchmarks.app_latency"

#: The viewport size the issue asks for.
VIEWPORT = (800, 600)
#: The joint histogram of a volume of this many points per side, and how long it may take.
HISTOGRAM_SIZE = 256
HISTOGRAM_TARGET_S = 2.0


@dataclass(frozen=True)
class AppTiming:
    dataset: str
    renderer: str
    edit_ms: float  # median TF edit -> full frame shown
    edit_frame_ms: float  # median render time of those frames (the renderer's own clock)
    drag_fps: float  # preview frames shown per second while a TF point is dragged
    rotate_fps: float  # frames shown per second while the camera turns
    settle_ms: float  # median mouse release -> full frame shown
    preview_size: tuple[int, int]  # the size of the preview frames seen while rotating
    rest_release_ms: float = math.nan  # a rotation that rests 0.4 s before its release: release -> full frame
    duplicate_frames: int = 0  # full frames that repeated the one before them (same camera, same TF)
    drag_preview_size: tuple[int, int] = (
        0,
        0,
    )  # the size of the preview frames seen while a TF point is dragged

    @property
    def preview_fraction(self) -> float:
        """The rotating previews' share of the viewport's pixels."""
        return self.preview_size[0] * self.preview_size[1] / (VIEWPORT[0] * VIEWPORT[1])

    @property
    def drag_preview_fraction(self) -> float:
        """The TF drag's previews' share of the viewport's pixels."""
        return self.drag_preview_size[0] * self.drag_preview_size[1] / (VIEWPORT[0] * VIEWPORT[1])


class _Probe:
    """Counts the frames a window shows and remembers the newest full one."""

    def __init__(self, window) -> None:
        self.shown: list[tuple[float, object]] = []
        self.full: list[tuple[float, object]] = []
        window.frameShown.connect(lambda f: self.shown.append((time.perf_counter(), f)))
        window.fullFrameShown.connect(lambda f: self.full.append((time.perf_counter(), f)))


def _full_frame_after(
    app, window, probe: _Probe, act: Callable[[], None], timeout_s: float
) -> tuple[float, float]:
    """Run `act`, wait for the full frame of the newest request; (ms to it, its render ms)."""
    count = len(probe.full)
    start = time.perf_counter()
    act()
    serial = window.service.latest_serial
    ok = wait(app, lambda: any(f.serial >= serial for _, f in probe.full[count:]), timeout_s)
    if not ok:
        raise TimeoutError(f"no full frame within {timeout_s:g} s")
    t, frame = next((t, f) for t, f in probe.full[count:] if f.serial >= serial)
    return (t - start) * 1000.0, frame.ms


def _move_point(tf, fraction: float, base) -> None:
    """Move the TF's highest opacity point a little along the value axis (an editor gesture), to
    `fraction` of the way across the middle fifth of its span in the TF's `base` points: from the
    base, so that the TF does not drift from edit to edit (where the peak was the last point, each
    edit moved it towards its neighbour and bonsai's ramp ended 30 times steeper)."""
    points = np.array(base, dtype=np.float64)
    peak = int(np.argmax(points[:, 1]))
    lo = points[peak - 1, 0] if peak > 0 else points[peak, 0]
    hi = points[peak + 1, 0] if peak + 1 < len(points) else points[peak, 0]
    points[peak, 0] = lo + (hi - lo) * (0.4 + 0.2 * fraction)
    tf.set_opacity_points(points)


def measure(
    app,
    volume,
    tf,
    renderer: str,
    dataset: str,
    edits: int = 7,
    gesture_s: float = 3.0,
    timeout_s: float = 120.0,
) -> AppTiming:
    """Open `volume` with `tf` and `renderer` in a fresh window at VIEWPORT and time it."""
    from volren.app.core.loading import LoadedInput
    from volren.app.window.main_window import MainWindow

    window = MainWindow()
    window.show_error_dialogs = False
    errors: list[str] = []
    window.errorReported.connect(lambda _t, m: errors.append(m))
    window.viewport.setFixedSize(*VIEWPORT)
    window.show()
    probe = _Probe(window)
    try:
        requested = None if renderer == "auto" else renderer  # auto: what the app opens with by default
        _full_frame_after(
            app,
            window,
            probe,
            lambda: window.files.apply_loaded(LoadedInput(volume, tf), requested),
            timeout_s,
        )
        if errors or window.state.renderer != (requested or window.state.renderer):
            raise RuntimeError(
                f"{renderer} could not show {dataset}: {'; '.join(errors) or window.state.renderer}"
            )
        if requested is None:
            renderer = f"{window.state.renderer} (auto)"
        state = window.state
        base = state.transfer_function.opacity_points.copy()
        edit_ms, frame_ms = [], []
        for i in range(edits + 1):
            ms, rendered = _full_frame_after(
                app,
                window,
                probe,
                lambda i=i: _move_point(state.transfer_function, (i % 2) * 1.0, base),
                timeout_s,
            )
            if i:  # the first edit builds tables that later edits reuse or rebuild alike
                edit_ms.append(ms)
                frame_ms.append(rendered)

        def gesture(step: Callable[[int], None]) -> float:
            """Call step(k) at 60 Hz for gesture_s inside an interaction; frames shown per second."""
            count = len(probe.shown)
            state.begin_interaction()
            elapsed = drive_at_60hz(app, step, gesture_s)
            shown = len(probe.shown) - count
            state.end_interaction()
            return shown / elapsed

        drag_fps = gesture(lambda k: _move_point(state.transfer_function, (k % 60) / 59.0, base))
        drag_previews = [f for _, f in probe.shown[-5:] if not f.full]
        drag_preview = (drag_previews[-1].width, drag_previews[-1].height) if drag_previews else (0, 0)
        wait(
            app,
            lambda: bool(probe.full) and probe.full[-1][1].serial == window.service.latest_serial,
            timeout_s,
        )
        settle = []
        rotate_fps = []
        preview = (0, 0)
        for _ in range(3):
            fps = gesture(lambda _k: state.set_camera(state.camera.azimuth(2.0)))
            rotate_fps.append(fps)
            previews = [f for _, f in probe.shown[-5:] if not f.full]
            if previews:
                preview = (previews[-1].width, previews[-1].height)
            released = time.perf_counter()
            wait(
                app,
                lambda: bool(probe.full) and probe.full[-1][1].serial == window.service.latest_serial,
                timeout_s,
            )
            settle.append((probe.full[-1][0] - released) * 1000.0)

        # a rotation that rests before its release (the settle timer draws the full frame, then the
        # release must not draw it again): release -> the newest full frame, and full frames of
        # the final camera beyond the first count as duplicates
        count = len(probe.full)
        state.begin_interaction()
        for _ in range(10):
            state.set_camera(state.camera.azimuth(2.0))
            wait(app, lambda: False, 1 / 60)
        wait(app, lambda: False, 0.4)
        released = time.perf_counter()
        state.end_interaction()
        wait(
            app,
            lambda: bool(probe.full) and probe.full[-1][1].serial == window.service.latest_serial,
            timeout_s,
        )
        wait(app, lambda: False, 0.5)  # a second full frame would come within the settle time
        rest_release = max(0.0, (probe.full[-1][0] - released) * 1000.0)
        final = state.camera
        duplicates = max(0, sum(1 for _, f in probe.full[count:] if f.camera == final) - 1)
        return AppTiming(
            dataset,
            renderer,
            statistics.median(edit_ms),
            statistics.median(frame_ms),
            drag_fps,
            statistics.median(rotate_fps),
            statistics.median(settle),
            preview,
            rest_release,
            duplicates,
            drag_preview,
        )
    finally:
        window.shutdown()
        window.close()
        window.deleteLater()
        app.processEvents()


def joint_histogram_seconds(n: int = HISTOGRAM_SIZE, repeats: int = 3) -> float:
    """Seconds (best of `repeats`, kernels compiled first) for the joint histogram of a random n^3
    uint8 volume, every point counted (raises if it was subsampled: then it measures less work)."""
    from volren.app.core import joint_histogram as jh
    from volren.model.volume import UniformVolume

    values = np.random.default_rng(0).integers(0, 256, size=(n, n, n), dtype=np.uint8)
    jh.joint_histogram(UniformVolume(values[:8, :8, :8]))
    best = math.inf
    for _ in range(repeats):
        jh.clear_cache()
        volume = UniformVolume(values)
        start = time.perf_counter()
        hist = jh.joint_histogram(volume)
        best = min(best, time.perf_counter() - start)
        if hist.stride != 1 or hist.counts.sum() + hist.above != values.size:
            raise RuntimeError(f"the {n}^3 histogram was not computed in full (stride {hist.stride})")
    jh.clear_cache()
    return best


def histogram_line(n: int, seconds: float) -> str:
    verdict = "within" if seconds < HISTOGRAM_TARGET_S else "OVER"
    return (
        f"Joint histogram (2D TF editor) of a {n}^3 uint8 volume, every point: {seconds:.2f} s, best of 3 "
        f"({verdict} the app's target of {HISTOGRAM_TARGET_S:g} s)."
    )


NOTE = (
    "The app's window ({platform} platform) with a {w}x{h} viewport, the scene's {style} TF. "
    "*TF edit -> frame*: an opacity point moves (one finished edit), until the full-quality frame is "
    "shown; *its render ms*: the renderer's own time for that frame. *fps*: frames shown per second "
    "while a TF point is dragged or the camera turns 2 degrees every 16 ms (previews at reduced size). "
    "*release -> full frame*: from the end of the rotation to the full-quality frame (includes the "
    "150 ms settle delay). *preview pixels*: the previews' share of the viewport's pixels (while "
    "dragging a TF point / while rotating; previews also use the `interactive` quality level and, in a "
    "TF drag, the renderer's `tf_drag_options`). "
    "*after a rest*: a rotation that rests 0.4 s before its release, release -> full frame (0 when "
    "the settle timer drew it already); *duplicates*: full frames that repeated the one before them."
)

HEADER = (
    "| dataset | renderer | TF edit -> frame ms | its render ms | fps, TF drag | fps, rotating "
    "| release -> full frame ms | preview size, TF drag / rotating | preview pixels, TF drag / rotating "
    "| after a rest ms | duplicates |"
    "\n|---|---|---|---|---|---|---|---|---|---|---|"
)


def markdown_row(t: AppTiming) -> str:
    return (
        f"| {t.dataset} | {t.renderer} | {t.edit_ms:.0f} | {t.edit_frame_ms:.0f} | {t.drag_fps:.1f} "
        f"| {t.rotate_fps:.1f} | {t.settle_ms:.0f} "
        f"| {t.drag_preview_size[0]}x{t.drag_preview_size[1]} / {t.preview_size[0]}x{t.preview_size[1]} "
        f"| {100 * t.drag_preview_fraction:.0f}% / {100 * t.preview_fraction:.0f}% "
        f"| {t.rest_release_ms:.0f} | {t.duplicate_frames} |"
    )


def measure_all(args: argparse.Namespace) -> int:
    """The latency table of each dataset and renderer, then the joint histogram's time."""
    shared = shared_folder(args.shared)
    datasets = [d for d in args.datasets.split(",") if d]
    unknown = [d for d in datasets if d not in SCENES]
    if unknown:
        raise VolrenError(f"unknown datasets {unknown}; choose from {', '.join(SCENES)}")
    if args.edits < 1 or not (math.isfinite(args.seconds) and args.seconds > 0):
        raise VolrenError("--edits must be at least 1 and --seconds positive")
    app = application()
    lines = [HEADER]
    print(HEADER, flush=True)
    for dataset in datasets:
        volume, tf = scene_inputs(shared, dataset, args.style)
        for renderer in [r for r in args.renderers.split(",") if r]:
            lines.append(
                markdown_row(measure(app, volume, tf.copy(), renderer, dataset, args.edits, args.seconds))
            )
            print(lines[-1], flush=True)
    if args.histogram_size > 0:
        lines += ["", histogram_line(args.histogram_size, joint_histogram_seconds(args.histogram_size))]
        print("\n" + lines[-1], flush=True)
    if args.out:
        note = NOTE.format(w=VIEWPORT[0], h=VIEWPORT[1], style=args.style, platform=app.platformName())
        out = Path(args.out)
        try:
            out.mkdir(parents=True, exist_ok=True)
            (out / "app_latency.md").write_text(note + "\n\n" + "\n".join(lines) + "\n")
        except OSError as exc:
            raise VolrenError(f"{args.out}: cannot write: {exc.strerror or exc}") from None
    return 0


def main(argv: list[str] | None = None) -> int:
    a = argparse.ArgumentParser(prog=COMMAND, description="desktop app: TF edit -> new frame latency, frames per "
                                "second rotating")  # fmt: skip
    a.add_argument("--shared", help="the folder with data/ and scenes/ (default: $VOLREN_SHARED)")
    a.add_argument("--datasets", default="ironProt,bonsai", help="comma-separated (default ironProt,bonsai)")
    a.add_argument("--renderers", default="slicer,vtk", help="comma-separated (default slicer,vtk)")
    a.add_argument("--style", default="smooth", help="TF style of the scenes (default smooth)")
    a.add_argument("--edits", type=int, default=7, help="timed TF edits, median reported (default 7)")
    a.add_argument("--seconds", type=float, default=3.0, help="length of each drag gesture (default 3 s)")
    a.add_argument(
        "--histogram-size",
        type=int,
        default=HISTOGRAM_SIZE,
        help="time the 2D TF editor's joint histogram of an N^3 volume (default 256; 0: not)",
    )
    a.add_argument("--out", help="folder to write app_latency.md into")
    return run(measure_all, a, argv)


if __name__ == "__main__":
    sys.exit(main())
