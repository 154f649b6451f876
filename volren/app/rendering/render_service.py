"""Rendering off the GUI thread: one worker thread owns the renderer; the newest request wins.

Why a dedicated thread rather than a pool: VTK and OpenGL objects belong to the thread that made
their context, so the renderer is created, fed (volume, TF, settings), used and released in the
same worker thread for its whole life. The GUI thread only ever hands over immutable requests.

Why "newest only": while the mouse drags, requests come faster than frames. A request waits in a
one-slot mailbox; a newer one replaces it, and a renderer that reports progress is interrupted
as soon as a newer request is waiting (its progress callback raises). So the frame being drawn
always belongs to the latest camera, and the GUI never waits for the renderer.

The transfer function is the one mutable input; each request carries a private copy made on the
GUI thread, keyed by (identity, version) of the original so the renderer is updated only when the
TF actually changed (`tf_key`: a TF per label or per channel also by the 1D TFs in it, edited in place).
"""

from __future__ import annotations

import sys
import threading
import time
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from PyQt5.QtCore import QObject, QThread, pyqtSignal, pyqtSlot

from volren.io.image_io import to_png_pixels
from volren.model.camera import Camera
from volren.model.channels import ChannelTransferFunction
from volren.model.labels import LabelTransferFunction
from volren.model.settings import RenderSettings
from volren.model.transfer_function_2d import TransferFunction
from volren.model.volume import Volume
from volren.renderers.base import Renderer, render_frame

#: What tells one state of a TF from another: its identity and version(s).
TFKey = tuple[int, ...]
#: A TF a frame is drawn with: 1D, 2D, one per label (RTVG chapter 16) or one per channel (Max 1995).
DrawnTF = TransferFunction | LabelTransferFunction | ChannelTransferFunction


def tf_key(tf: DrawnTF) -> TFKey:
    """(identity, version) of `tf`; for a TF per label also its base TF's and its labels' own TFs'
    (`LabelTransferFunction.state`), and for a TF per channel each channel's TF's: the 1D editor
    edits those in place without changing the combined TF's own version."""
    if isinstance(tf, LabelTransferFunction):
        return (id(tf), id(tf.base), *tf.state())
    if isinstance(tf, ChannelTransferFunction):
        return (id(tf), tf.version, *(n for channel in tf.tfs for n in (id(channel), channel.version)))
    return (id(tf), tf.version)


@dataclass(frozen=True, eq=False)
class RenderRequest:
    """Everything one frame needs; immutable apart from `tf`, which is a private copy."""

    serial: int
    renderer: str
    volume: Volume
    tf: DrawnTF
    tf_key: TFKey
    settings: RenderSettings
    camera: Camera
    width: int
    height: int
    full: bool
    background: tuple[float, float, float]
    #: a warm-up: the renderer is set up and draws a tiny frame that nobody sees (`RenderService.warm`)
    warm: bool = False


@dataclass(frozen=True, eq=False)
class Frame:
    """A finished frame, already converted to 8-bit RGB over the background."""

    serial: int
    renderer: str
    width: int
    height: int
    ms: float
    full: bool
    rgb: NDArray[np.uint8]
    camera: Camera
    settings: RenderSettings | None = (
        None  #: what it was drawn with (previews may be cheaper than the state's)
    )
    setup: bool = False  #: its time includes a renderer set-up (a new renderer or volume)
    tf_changed: bool = False  #: the renderer was given a new TF for it (its tables, an error estimate)
    volume: Volume | None = None  #: what it drew (the crop applied), to tell a frame of the current state
    tf_key: TFKey | None = None  #: (identity, version) of the TF it drew (`tf_key`)


#: The side of a warm-up's frame (`RenderService.warm`): enough to build tables and compile nothing.
WARM_SIZE = 8
#: Frames slower than this report their progress, at most this often.
PROGRESS_INTERVAL_S = 0.25
#: A frame is abandoned for a newer request (`_Mailbox.overtakes`) only after it ran this long since its first progress
#: report. Interrupting every frame that a newer request overtakes would starve a continuous drag
#: (requests at 60 Hz, frames at 20 Hz: nothing would ever be shown); a short frame is finished and
#: shown, a slow one (the reference renderer) gives way. Counted from the first report, not the
#: start: a renderer's set-up for a new TF (tetra's tables, 0.3 s on oxygen) comes before it, and
#: abandoning a frame whose set-up is paid starved a TF drag (tetra showed nothing until release).
INTERRUPT_AFTER_S = 0.25


class _Superseded(Exception):
    """Raised from the progress callback to abandon a frame nobody will see."""


class _Mailbox:
    """One slot shared by the GUI thread (puts) and the worker (takes); put replaces."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._request: RenderRequest | None = None
        self.closed = False

    def put(self, request: RenderRequest) -> None:
        with self._lock:
            if not self.closed:
                self._request = request

    def take(self) -> RenderRequest | None:
        with self._lock:
            request, self._request = self._request, None
            return None if self.closed else request

    def waiting(self) -> bool:
        with self._lock:
            return self._request is not None or self.closed

    def overtakes(self, running: RenderRequest) -> bool:
        """Whether what waits should stop the `running` frame: a full frame gives way to any newer
        request, a preview only to a full frame (or to closing). A preview that gave way to the
        next preview would starve a drag whose previews take longer than its requests come (a 2D
        TF's, 0.4-1 s at first): none would be shown, and the frame cost model, which sizes
        previews from the ones finished, would never learn to make them smaller."""
        with self._lock:
            if self.closed:
                return True
            return self._request is not None and (running.full or self._request.full)

    def close(self) -> None:
        with self._lock:
            self.closed = True
            self._request = None


RendererFactory = Callable[[str], Renderer]

#: Renderers the worker keeps set up: the still frames' and the previews' (`preview_choice`), so
#: that alternating between them does not rebuild either's per-volume structures.
RENDERERS_KEPT = 2


@dataclass(eq=False)
class _Slot:
    """A renderer and what it was last given."""

    renderer: Renderer
    volume: Volume | None = None
    tf_key: TFKey | None = None
    settings: RenderSettings | None = None


def _registry_factory(name: str) -> Renderer:
    from volren.renderers.registry import registry

    return registry.create(name)


class RenderWorker(QObject):
    """Lives in the render thread; owns the renderer and what was last given to it."""

    frameReady = pyqtSignal(object)  # Frame
    failed = pyqtSignal(object, str)  # RenderRequest, one-line reason
    progressed = pyqtSignal(int, str, float)  # serial, renderer, fraction done (slow frames only)
    preparing = pyqtSignal(int, str)  # serial, renderer: a new renderer or volume is being set up
    warmed = pyqtSignal(str)  # renderer: a warm-up is done (or failed: its first real frame will say why)

    def __init__(self, mailbox: _Mailbox, factory: RendererFactory = _registry_factory) -> None:
        super().__init__()
        self._mailbox = mailbox
        self._factory = factory
        self._slots: OrderedDict[str, _Slot] = OrderedDict()  # by renderer name, most recently used last

    @pyqtSlot()
    def process(self) -> None:
        """Render what waits in the mailbox until it is empty (extra wake-ups find it empty)."""
        while True:
            request = self._mailbox.take()
            if request is None:
                return
            try:
                frame = self._render(request)
            except Exception as exc:  # noqa: BLE001 - a renderer must not take the app down
                if request.warm:
                    self.warmed.emit(request.renderer)
                    continue
                if isinstance(exc, _Superseded) or self._mailbox.waiting():
                    continue  # interrupted (or failing) on the way to a newer frame
                self._release(request.renderer)  # a renderer that raised may be in any state: start afresh
                self.failed.emit(request, _one_line(exc))
                continue
            if request.warm:
                self.warmed.emit(request.renderer)
            else:
                self.frameReady.emit(frame)

    def _sync(self, request: RenderRequest) -> tuple[Renderer, bool, bool]:
        """The request's renderer, given what it needs; whether that meant a set-up (a new
        renderer or volume: that frame's time says little about the next ones'); and whether it
        was given a new TF (that frame also pays for what the renderer keeps per TF)."""
        slot = self._slots.get(request.renderer)
        setup = slot is None or slot.volume is not request.volume
        if setup and not request.warm:
            # set-up ahead (the renderer's imports, its per-volume structures, its first frame's tables):
            # the GUI says so when no frame follows within PREPARING_AFTER_S
            self.preparing.emit(request.serial, request.renderer)
        if slot is None:
            slot = _Slot(self._factory(request.renderer))
            self._slots[request.renderer] = slot
            while len(self._slots) > RENDERERS_KEPT:  # the least recently used one goes
                self._release(next(iter(self._slots)))
        self._slots.move_to_end(request.renderer)
        renderer = slot.renderer
        if slot.settings != request.settings:
            renderer.set_settings(request.settings)
            slot.settings = request.settings
        if slot.volume is not request.volume:
            renderer.set_volume(request.volume)
            slot.volume = request.volume
        tf_changed = slot.tf_key != request.tf_key
        if tf_changed:
            renderer.set_transfer_function(request.tf)
            slot.tf_key = request.tf_key
        return renderer, setup, tf_changed

    def _render(self, request: RenderRequest) -> Frame:
        renderer, setup, tf_changed = self._sync(request)

        start = time.perf_counter()
        last_report = [start]
        first_report: list[float] = []

        def progress(fraction: float) -> None:
            now = time.perf_counter()
            if not first_report:
                first_report.append(now)
            if (
                fraction < 1.0
                and now - first_report[0] > INTERRUPT_AFTER_S
                and self._mailbox.overtakes(request)
            ):
                raise _Superseded()
            if now - last_report[0] > PROGRESS_INTERVAL_S:  # only slow frames, and not too often
                last_report[0] = now
                self.progressed.emit(request.serial, request.renderer, float(fraction))

        image, stats = render_frame(
            renderer, request.camera, request.width, request.height, progress, label=request.renderer
        )
        rgb = to_png_pixels(image, request.background)
        return Frame(
            request.serial,
            request.renderer,
            request.width,
            request.height,
            stats.ms,
            request.full,
            rgb,
            request.camera,
            request.settings,
            setup,
            tf_changed,
            request.volume,
            request.tf_key,
        )

    def _release(self, name: str) -> None:
        slot = self._slots.pop(name, None)
        if slot is not None:
            try:
                slot.renderer.release()
            except Exception as exc:  # noqa: BLE001 - releasing must not fail the next frame
                print(f"volren: warning: releasing the renderer failed: {_one_line(exc)}", file=sys.stderr)

    @pyqtSlot()
    def stop(self) -> None:
        """Release the renderers here, in their own thread, then end the thread's event loop."""
        for name in list(self._slots):
            self._release(name)
        thread = self.thread()
        if thread is not None:
            thread.quit()


def _one_line(exc: BaseException) -> str:
    from volren.errors import VolrenError

    text = " ".join(str(exc).split())
    if isinstance(exc, VolrenError):
        return text
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


#: Threads that did not stop in time are kept here: destroying a running QThread aborts the process.
_orphans: list[tuple[QThread, RenderWorker]] = []


class RenderService(QObject):
    """The GUI thread's handle on the render thread: submit requests, receive frames."""

    frameReady = pyqtSignal(object)  # Frame
    renderFailed = pyqtSignal(object, str)  # RenderRequest, one-line reason
    progressed = pyqtSignal(int, str, float)  # serial, renderer, fraction done (slow frames only)
    preparing = pyqtSignal(int, str)  # serial, renderer: set-up of a new renderer or volume began
    _wake = pyqtSignal()
    _stop = pyqtSignal()

    def __init__(self, parent: QObject | None = None, factory: RendererFactory = _registry_factory) -> None:
        super().__init__(parent)
        self._mailbox = _Mailbox()
        self._serial = 0
        self._running = True
        self._thread = QThread()
        self._thread.setObjectName("volren-render")
        self._worker = RenderWorker(self._mailbox, factory)
        self._worker.moveToThread(self._thread)
        self._wake.connect(self._worker.process)
        self._stop.connect(self._worker.stop)
        self._worker.frameReady.connect(self._on_frame)
        self._worker.failed.connect(self._on_failed)
        self._worker.progressed.connect(self._on_progress)
        self._worker.preparing.connect(self._on_preparing)
        self._worker.warmed.connect(self._on_warmed)
        self._warming = False
        self._thread.start()

    @property
    def warming(self) -> bool:
        """Whether a warm-up was asked for and neither it nor a later frame has finished."""
        return self._warming

    @property
    def latest_serial(self) -> int:
        """The serial of the newest request; a frame with this serial is up to date."""
        return self._serial

    def submit(
        self,
        renderer: str,
        volume: Volume,
        tf: DrawnTF,
        settings: RenderSettings,
        camera: Camera,
        width: int,
        height: int,
        full: bool = True,
        background: tuple[float, float, float] = (0.0, 0.0, 0.0),
    ) -> int:
        """Queue a frame, replacing any request not yet started; returns its serial."""
        if not self._running:
            return self._serial
        self._serial += 1
        request = RenderRequest(
            self._serial,
            renderer,
            volume,
            tf.copy(),
            tf_key(tf),
            settings,
            camera,
            int(width),
            int(height),
            full,
            background,
        )
        self._mailbox.put(request)
        self._wake.emit()
        return self._serial

    def warm(self, renderer: str, volume: Volume, tf: DrawnTF, settings: RenderSettings) -> None:
        """Set `renderer` up for `volume`, `tf` and `settings` now, while nothing else waits: it
        draws a WARM_SIZE frame that is not shown, so that its first real frame (the first preview
        of a drag, by another renderer than the still frames') does not pay the set-up (0.7 s for
        shearwarp's first bonsai preview). Any request replaces a warm-up that has not started; a
        warm-up takes no serial, so `latest_serial` still names the newest frame to show."""
        if not self._running:
            return
        request = RenderRequest(0, renderer, volume, tf.copy(), tf_key(tf), settings,
                                Camera.orbit(volume.bounds), WARM_SIZE, WARM_SIZE, False, (0.0, 0.0, 0.0), warm=True)  # fmt: skip
        self._warming = True
        self._mailbox.put(request)
        self._wake.emit()

    @pyqtSlot(str)
    def _on_warmed(self, _renderer: str) -> None:
        self._warming = False

    @pyqtSlot(object)
    def _on_frame(self, frame: Frame) -> None:
        self._warming = False  # a warm-up replaced before it started ends here too
        if self._running:
            self.frameReady.emit(frame)

    @pyqtSlot(int, str, float)
    def _on_progress(self, serial: int, renderer: str, fraction: float) -> None:
        if self._running and serial == self._serial:
            self.progressed.emit(serial, renderer, fraction)

    @pyqtSlot(int, str)
    def _on_preparing(self, serial: int, renderer: str) -> None:
        if self._running:
            self.preparing.emit(serial, renderer)

    @pyqtSlot(object, str)
    def _on_failed(self, request: RenderRequest, message: str) -> None:
        if self._running:
            self.renderFailed.emit(request, message)

    def shutdown(self, timeout_ms: int = 30000) -> None:
        """Drop waiting requests, release the renderer in its thread and stop the thread."""
        if not self._running:
            return
        self._running = False
        self._mailbox.close()
        self._stop.emit()
        if not self._thread.wait(timeout_ms):
            print("volren: warning: the renderer did not stop in time", file=sys.stderr)
            _orphans.append((self._thread, self._worker))
