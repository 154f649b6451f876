"""The app's gestures with the renderer `auto` picks: previews per second, their share of the
pixels, release to full frame, the GUI thread's longest stall, and open to first full frame.

Why a table of its own: people judge a viewer by how it follows the hand. A preview rate of 10
per second at a quarter of the pixels or more is the floor for a drag that feels attached to the
mouse, a still frame within 0.6 s of the release for one that feels finished, and a GUI thread
that answers within 50 ms for a window that does not feel frozen (`TARGETS`). The window is the
real `MainWindow` (offscreen where there is no display); each gesture changes the state at 60 Hz
inside an interaction, as the viewport, the TF editors and the crop handles do:

- **rotate**: the camera turns 2 degrees a step;
- **TF point**: the 1D TF's highest opacity point slides along the value axis;
- **2D widget**: after "Use a 2D transfer function" (the 1D TF as a 2D band) a Gaussian widget
  added over it moves along the value axis;
- **crop face**: the crop box's upper x face moves inwards and back;
- **clip plane**: an oblique clip plane through the volume moves along its normal and back (the
  clipping panel's position slider, the view's plane handle).

The GUI thread's stall is the largest gap between the ticks of a 5 ms timer on it, less 5 ms:
whatever holds the thread (or the interpreter's lock) that long delays every click and repaint.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from volren.app.timing.drive import application, drive_at_60hz, wait

#: `application` is the QApplication a measurement runs in (`drive`), named here for `volren bench app`.
__all__ = [
    "HEADER",
    "TARGETS",
    "VIEWPORT",
    "GestureTiming",
    "SceneTiming",
    "StallProbe",
    "application",
    "markdown_rows",
    "measure_scene",
    "note",
    "run_gesture",
    "settle",
]

#: The viewport the interaction targets were set on: a maximised window on a 1080p screen.
VIEWPORT = (947, 896)
#: (previews per second, their share of the pixels, release -> full frame ms, GUI stall ms,
#: end of loading -> first full frame ms): what each gesture and an opening must reach.
TARGETS = {
    "previews_per_s": 10.0,
    "preview_share": 0.25,
    "release_ms": 600.0,
    "stall_ms": 50.0,
    "open_ms": 1500.0,
}
#: The GUI thread's stall probe ticks this often (ms).
TICK_MS = 5


@dataclass(frozen=True)
class GestureTiming:
    gesture: str
    previews_per_s: float
    preview_share: float  # median share of the viewport's pixels of the previews shown
    release_ms: float  # release -> the full frame of the final state shown
    stall_ms: float  # the GUI thread's longest stall, from the gesture's start to that full frame
    still_renderer: str
    preview_renderer: str

    def holds(self) -> bool:
        return (self.previews_per_s >= TARGETS["previews_per_s"] and self.preview_share >= TARGETS["preview_share"]
                and self.release_ms <= TARGETS["release_ms"] and self.stall_ms <= TARGETS["stall_ms"])  # fmt: skip


@dataclass(frozen=True)
class SceneTiming:
    scene: str
    renderer: str  # what auto picked for the scene's TF
    open_ms: float  # apply_loaded -> first full frame shown
    open_stall_ms: float
    gestures: tuple[GestureTiming, ...]


class StallProbe:
    """The GUI thread's longest gap between the ticks of a TICK_MS timer, less TICK_MS."""

    def __init__(self) -> None:
        from PyQt5.QtCore import QTimer

        self._timer = QTimer()
        self._timer.setInterval(TICK_MS)
        self._timer.timeout.connect(self._tick)
        self._last = 0.0
        self.worst_ms = 0.0

    def start(self) -> None:
        self._last = time.perf_counter()
        self.worst_ms = 0.0
        self._timer.start()

    def stop(self) -> float:
        self._tick()
        self._timer.stop()
        return self.worst_ms

    def _tick(self) -> None:
        now = time.perf_counter()
        self.worst_ms = max(self.worst_ms, (now - self._last) * 1000.0 - TICK_MS)
        self._last = now


def settle(app, window, timeout_s: float) -> None:
    """Wait until the full frame of the newest request is on screen and no warm-up runs."""

    def done() -> bool:
        frame = window.viewport.frame
        return (not window.service.warming and frame is not None and frame.full
                and frame.serial == window.service.latest_serial)  # fmt: skip

    if not wait(app, done, timeout_s):
        raise TimeoutError(f"no full frame within {timeout_s:g} s")


def _share(frame) -> float:
    return frame.width * frame.height / (VIEWPORT[0] * VIEWPORT[1])


def run_gesture(
    app, window, name: str, step: Callable[[int], None], seconds: float, timeout_s: float
) -> GestureTiming:
    """`step(k)` at 60 Hz for `seconds` inside an interaction, then release; what the person saw."""
    state, stall = window.state, StallProbe()
    shown: list[tuple[float, object]] = []
    record = lambda frame: shown.append((time.perf_counter(), frame))  # noqa: E731
    window.frameShown.connect(record)
    try:
        stall.start()
        state.begin_interaction()
        elapsed = drive_at_60hz(app, step, seconds)
        previews = [f for _, f in shown if not f.full]
        released = time.perf_counter()
        state.end_interaction()
        serial = window.service.latest_serial

        def final_shown() -> bool:
            return any(f.full and f.serial >= serial for _, f in shown)

        if not wait(app, final_shown, timeout_s):
            raise TimeoutError(f"{name}: no full frame within {timeout_s:g} s of the release")
        done, final = next((t, f) for t, f in shown if f.full and f.serial >= serial)
        return GestureTiming(
            name,
            len(previews) / elapsed,
            statistics.median(_share(f) for f in previews) if previews else 0.0,
            (done - released) * 1000.0,
            stall.stop(),
            final.renderer,
            previews[-1].renderer if previews else "-",
        )
    finally:
        window.frameShown.disconnect(record)


def _slide(points: np.ndarray, fraction: float) -> np.ndarray:
    """The opacity points with the highest one moved to `fraction` of the way between its neighbours."""
    points = np.array(points, dtype=np.float64)
    peak = int(np.argmax(points[:, 1]))
    lo = points[peak - 1, 0] if peak > 0 else points[peak, 0]
    hi = points[peak + 1, 0] if peak + 1 < len(points) else points[peak, 0]
    points[peak, 0] = lo + (hi - lo) * (0.3 + 0.4 * fraction)
    return points


def _swing(k: int, period: int = 60) -> float:
    """0 -> 1 -> 0 over `period` steps: a gesture that goes and comes back."""
    phase = (k % period) / period
    return 2 * phase if phase < 0.5 else 2 - 2 * phase


def measure_scene(app, volume, tf, scene: str, seconds: float = 3.0, timeout_s: float = 120.0) -> SceneTiming:
    """Open `volume` with `tf` (renderer `auto`) at VIEWPORT; time the opening and each gesture."""
    from volren.app.core.loading import LoadedInput, prepare_for_rendering
    from volren.app.window.main_window import MainWindow
    from volren.model.transfer_function import TransferFunction1D
    from volren.model.transfer_function_2d import TFWidget

    window = MainWindow()
    window.show_error_dialogs = False
    errors: list[str] = []
    window.errorReported.connect(lambda _t, m: errors.append(m))
    window.viewport.setFixedSize(*VIEWPORT)
    window.show()
    prepare_for_rendering(volume)  # the app's loader does it in its thread, before the volume is shown
    try:
        stall = StallProbe()
        stall.start()
        start = time.perf_counter()
        window.files.apply_loaded(LoadedInput(volume, tf))
        serial = window.service.latest_serial
        full: list[float] = []
        window.fullFrameShown.connect(
            lambda f: full.append(time.perf_counter()) if f.serial >= serial else None
        )
        if not wait(app, lambda: bool(full), timeout_s):
            raise TimeoutError(f"{scene}: no first frame within {timeout_s:g} s")
        open_ms, open_stall = (full[0] - start) * 1000.0, stall.stop()
        if errors:
            raise RuntimeError(f"{scene}: {'; '.join(errors)}")
        state = window.state
        renderer = state.renderer
        settle(app, window, timeout_s)  # the previews' renderer set up
        gestures = [run_gesture(app, window, "rotate", lambda _k: state.set_camera(state.camera.azimuth(2.0)),
                                seconds, timeout_s)]  # fmt: skip
        one_d = state.transfer_function
        assert isinstance(one_d, TransferFunction1D)
        base = one_d.opacity_points.copy()
        gestures.append(run_gesture(app, window, "TF point", lambda k: one_d.set_opacity_points(_slide(base, _swing(k))),
                                    seconds, timeout_s))  # fmt: skip
        one_d.set_opacity_points(base)
        bounds = volume.bounds
        xmin, xmax = float(bounds[0]), float(bounds[1])

        def crop(k: int) -> None:
            box = list(bounds)
            box[1] = xmax - 0.4 * (xmax - xmin) * _swing(k)
            state.set_crop(tuple(box))

        gestures.append(run_gesture(app, window, "crop face", crop, seconds, timeout_s))
        state.set_crop(None)
        gestures.append(_clip_plane_gesture(app, window, volume, seconds, timeout_s))
        editor = window.docks.tf_panel.editor_2d
        editor.use_2d_transfer_function()
        two_d = state.transfer_function
        if two_d.dims == 2:
            (lo, hi), (_, gmax) = two_d.value_range, two_d.gradient_range
            blob = TFWidget.gaussian(
                (lo + 0.5 * (hi - lo), 0.5 * gmax), (0.08 * (hi - lo), 0.3 * gmax), (1.0, 0.6, 0.2), 0.5
            )
            index = two_d.add_widget(blob)
            settle(app, window, timeout_s)  # the renderer that draws 2D TFs, set up

            def move(k: int) -> None:
                center = (lo + (0.3 + 0.4 * _swing(k)) * (hi - lo), 0.5 * gmax)
                two_d.replace_widget(
                    index, TFWidget.gaussian(center, (0.08 * (hi - lo), 0.3 * gmax), (1.0, 0.6, 0.2), 0.5)
                )

            gestures.append(run_gesture(app, window, "2D widget", move, seconds, timeout_s))
        return SceneTiming(scene, renderer, open_ms, open_stall, tuple(gestures))
    finally:
        window.shutdown()
        window.close()
        window.deleteLater()
        app.processEvents()


def _clip_plane_gesture(app, window, volume, seconds: float, timeout_s: float) -> GestureTiming:
    """An oblique plane through the centre, moved along its normal from a quarter of the volume's
    depth along it to three quarters and back; the plane removed after."""
    from volren.model.clip_region import ClipPlane, ClipRegion

    state = window.state
    lo = np.asarray(volume.bounds[0::2], dtype=np.float64)
    hi = np.asarray(volume.bounds[1::2], dtype=np.float64)
    normal = np.array([1.0, 0.6, -0.4]) / np.linalg.norm([1.0, 0.6, -0.4])
    plain = state.settings

    def move(k: int) -> None:
        origin = lo + (hi - lo) * (0.25 + 0.5 * _swing(k))
        plane = ClipPlane(tuple(float(v) for v in origin), tuple(float(v) for v in normal))
        state.set_settings(plain.with_(clip=ClipRegion((plane,), plain.clip.box)))

    move(0)
    settle(app, window, timeout_s)  # a renderer that clips, set up
    timing = run_gesture(app, window, "clip plane", move, seconds, timeout_s)
    state.set_settings(plain)
    settle(app, window, timeout_s)
    return timing


HEADER = ("| scene | auto's renderer | open -> first full frame ms | gesture | previews/s | preview pixels "
          "| release -> full frame ms | longest GUI stall ms | still / preview renderer | meets the targets |\n"
          "|---|---|---:|---|---:|---:|---:|---:|---|---|")  # fmt: skip


def markdown_rows(t: SceneTiming) -> list[str]:
    rows = []
    for i, g in enumerate(t.gestures):
        opening = f"{t.open_ms:.0f} (stall {t.open_stall_ms:.0f})" if i == 0 else ""
        rows.append(f"| {t.scene if i == 0 else ''} | {t.renderer if i == 0 else ''} | {opening} | {g.gesture} "
                    f"| {g.previews_per_s:.1f} | {100 * g.preview_share:.0f}% | {g.release_ms:.0f} | {g.stall_ms:.0f} "
                    f"| {g.still_renderer} / {g.preview_renderer} | {'yes' if g.holds() else 'no'} |")  # fmt: skip
    return rows


NOTE = (
    "The app's window ({platform} platform) with a {w}x{h} viewport and the renderer `auto` picks for "
    "the scene's TF (no renderer or quality chosen). Each gesture changes the state at 60 Hz for {s:g} s "
    "inside an interaction: *previews/s* are the preview frames shown per second, *preview pixels* their "
    "median share of the viewport's pixels, *release -> full frame* the time from the release to the "
    "full frame of the final state, *longest GUI stall* the largest gap between the ticks of a 5 ms timer "
    "on the GUI thread (less 5 ms) from the gesture's start to that frame. Targets: >= {p:g} previews/s "
    "of >= {share:.0f} % of the pixels, the full frame <= {r:g} ms after the release, no stall over "
    "{st:g} ms; the first full frame <= {o:g} ms after the end of loading."
)


def note(platform: str, seconds: float) -> str:
    return NOTE.format(platform=platform, w=VIEWPORT[0], h=VIEWPORT[1], s=seconds, p=TARGETS["previews_per_s"],
                       share=100 * TARGETS["preview_share"], r=TARGETS["release_ms"], st=TARGETS["stall_ms"],
                       o=TARGETS["open_ms"])  # fmt: skip
