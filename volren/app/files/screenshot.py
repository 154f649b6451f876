"""File > Save Screenshot: a full-quality frame at a chosen resolution, rendered off the GUI thread.

Why not reuse the viewport's render thread: its mailbox keeps only the newest request, so the
next mouse move would replace (or interrupt) a large screenshot, and its frames go to the
viewport. A screenshot gets its own short-lived renderer instead, made, fed, used and released
in one pool thread (renderers own their GL context per thread and per instance), from a
snapshot of the view taken on the GUI thread: the person can go on editing while it renders.

The PNG holds what the viewport shows: the premultiplied frame over the view's background
(`volren.io.save_image`, the conversion every frame goes through).
"""

from __future__ import annotations

import os
import threading
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from PyQt5.QtCore import QObject, QRunnable, QThreadPool, pyqtSignal, pyqtSlot

from volren.app.core.loading import PathArg, one_line_error
from volren.app.core.state import ViewState
from volren.app.rendering.render_service import RendererFactory, _registry_factory
from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.settings import RenderSettings
from volren.model.transfer_function_2d import TransferFunction
from volren.model.volume import Volume
from volren.renderers.base import ProgressCallback


@dataclass(frozen=True, eq=False)
class ScreenshotJob:
    """One screenshot: where, how big, and a snapshot of the view (the TF is a private copy)."""

    path: Path
    width: int
    height: int
    renderer: str
    volume: Volume
    tf: TransferFunction
    settings: RenderSettings
    camera: Camera
    background: tuple[float, float, float]

    @classmethod
    def of_view(cls, state: ViewState, path: PathArg, width: int, height: int) -> ScreenshotJob:
        """The job for what `state` shows now (cropped volume included); VolrenError if nothing is."""
        volume, tf, camera = state.render_volume, state.transfer_function, state.camera
        if volume is None or tf is None or camera is None:
            raise VolrenError("nothing to render: open a volume first")
        if width < 1 or height < 1:
            raise VolrenError(f"a screenshot needs a positive size, got {width} x {height}")
        return cls(
            Path(path),
            int(width),
            int(height),
            state.renderer,
            volume,
            tf.copy(),
            state.settings,
            camera,
            state.background,
        )


def check_writable(path: PathArg) -> None:
    """Fail before rendering (which may take long) when the PNG cannot go there."""
    folder = Path(path).absolute().parent
    if not folder.is_dir():
        raise VolrenError(f"{path}: the folder {folder} does not exist")
    if not os.access(folder, os.W_OK):
        raise VolrenError(f"{path}: cannot write in {folder}")


def render_job(
    job: ScreenshotJob, factory: RendererFactory = _registry_factory, progress: ProgressCallback | None = None
) -> NDArray[np.float32]:
    """The premultiplied RGBA frame of `job`, from a renderer made for it and released after."""
    renderer = factory(job.renderer)
    try:
        renderer.set_settings(job.settings)
        renderer.set_volume(job.volume)
        renderer.set_transfer_function(job.tf)
        return np.asarray(renderer.render(job.camera, job.width, job.height, progress))
    finally:
        renderer.release()


def write_job(job: ScreenshotJob, image: NDArray[np.float32]) -> None:
    """The frame as PNG over the job's background."""
    from volren.io import save_image

    save_image(image, job.path, job.background)


class _Cancelled(Exception):
    """Raised from the renderer's progress callback when the screenshot is no longer wanted."""


class _Signals(QObject):
    """Lives in the GUI thread; emitting from the pool thread queues the call."""

    progressed = pyqtSignal(int, float)
    saved = pyqtSignal(int, str)
    failed = pyqtSignal(int, str)


class _ScreenshotTask(QRunnable):
    def __init__(
        self,
        serial: int,
        job: ScreenshotJob,
        factory: RendererFactory,
        signals: _Signals,
        stop: threading.Event,
    ) -> None:
        super().__init__()
        self._serial, self._job, self._factory, self._signals, self._stop = (
            serial,
            job,
            factory,
            signals,
            stop,
        )

    def _progress(self, fraction: float) -> None:
        if self._stop.is_set():
            raise _Cancelled()
        self._emit("progressed", float(fraction))

    def run(self) -> None:
        try:
            image = render_job(self._job, self._factory, self._progress)
            if self._stop.is_set():
                return
            write_job(self._job, image)
        except _Cancelled:
            return
        except BaseException as exc:  # noqa: BLE001 - every failure becomes a one-line message
            if not self._stop.is_set():
                self._emit("failed", one_line_error(exc))
            return
        self._emit("saved", str(self._job.path))

    def _emit(self, signal: str, payload: object) -> None:
        try:
            getattr(self._signals, signal).emit(self._serial, payload)
        except RuntimeError:  # the window closed while we rendered
            pass


class Screenshotter(QObject):
    """Runs `ScreenshotJob`s one at a time; `saved(path)`, `failed(message)` or, after `cancel()`,
    nothing. A new job abandons the one still running."""

    progressed = pyqtSignal(float)  # fraction done, from renderers that report it
    saved = pyqtSignal(str)
    failed = pyqtSignal(str)
    busyChanged = pyqtSignal(bool)

    def __init__(self, factory: RendererFactory = _registry_factory, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._factory = factory
        self._pool = QThreadPool(self)
        self._pool.setMaxThreadCount(1)
        self._signals = _Signals(self)
        self._signals.progressed.connect(self._on_progress)
        self._signals.saved.connect(self._on_saved)
        self._signals.failed.connect(self._on_failed)
        self._serial = 0
        self._stop: threading.Event | None = None

    @property
    def busy(self) -> bool:
        return self._stop is not None

    def start(self, job: ScreenshotJob) -> int:
        """Render and write `job` in the background; returns its serial."""
        self._abandon()
        self._serial += 1
        self._stop = threading.Event()
        self._pool.start(_ScreenshotTask(self._serial, job, self._factory, self._signals, self._stop))
        self.busyChanged.emit(True)
        return self._serial

    def cancel(self) -> bool:
        """Stop the running job (at its next progress report, or before writing)."""
        if not self.busy:
            return False
        self._abandon()
        self._serial += 1
        self.busyChanged.emit(False)
        return True

    def _abandon(self) -> None:
        if self._stop is not None:
            self._stop.set()
            self._stop = None

    @pyqtSlot(int, float)
    def _on_progress(self, serial: int, fraction: float) -> None:
        if serial == self._serial and self.busy:
            self.progressed.emit(fraction)

    @pyqtSlot(int, str)
    def _on_saved(self, serial: int, path: str) -> None:
        if serial == self._serial and self.busy:
            self._stop = None
            self.busyChanged.emit(False)
            self.saved.emit(path)

    @pyqtSlot(int, str)
    def _on_failed(self, serial: int, message: str) -> None:
        if serial == self._serial and self.busy:
            self._stop = None
            self.busyChanged.emit(False)
            self.failed.emit(message)

    def shutdown(self, timeout_ms: int = 30000) -> bool:
        """Stop the running job and wait for its thread (the renderer is released there)."""
        self._abandon()
        self._serial += 1
        return self._pool.waitForDone(timeout_ms)
