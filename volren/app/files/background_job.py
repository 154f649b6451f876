"""Long jobs that write a file (a screenshot, a movie) run in a pool thread, one at a time, with
progress and cancel, so the window stays responsive and the person can go on editing.

A job is a function `work(progress) -> path written`. `progress(fraction)` reports how far it is
and raises once the job is cancelled, which is how a renderer deep inside the work stops; the work
must write its file only after its last `progress` call (or write it atomically), so a cancelled
job leaves nothing behind.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

from PyQt5.QtCore import QObject, QRunnable, QThreadPool, pyqtSignal, pyqtSlot

from volren.app.core.loading import one_line_error
from volren.renderers.base import ProgressCallback

#: The work of one job: renders and writes, reporting through the callback; returns the path.
Work = Callable[[ProgressCallback], str]


class JobCancelled(Exception):
    """Raised from the progress callback when the job is no longer wanted."""


class _Signals(QObject):
    """Lives in the GUI thread; emitting from the pool thread queues the call."""

    progressed = pyqtSignal(int, float)
    saved = pyqtSignal(int, str)
    failed = pyqtSignal(int, str)


class _Task(QRunnable):
    def __init__(self, serial: int, work: Work, signals: _Signals, stop: threading.Event) -> None:
        super().__init__()
        self._serial, self._work, self._signals, self._stop = serial, work, signals, stop

    def _progress(self, fraction: float) -> None:
        if self._stop.is_set():
            raise JobCancelled()
        self._emit("progressed", float(fraction))

    def run(self) -> None:
        try:
            path = self._work(self._progress)
        except JobCancelled:
            return
        except BaseException as exc:  # noqa: BLE001 - every failure becomes a one-line message
            if not self._stop.is_set():
                self._emit("failed", one_line_error(exc))
            return
        if not self._stop.is_set():
            self._emit("saved", path)

    def _emit(self, signal: str, payload: object) -> None:
        try:
            getattr(self._signals, signal).emit(self._serial, payload)
        except RuntimeError:  # the window closed while we worked
            pass


class BackgroundJobs(QObject):
    """Runs jobs one at a time; each ends in `saved(path)`, `failed(message)` or, after
    `cancel()`, nothing. A new job abandons the one still running."""

    progressed = pyqtSignal(float)  # fraction done, from work that reports it
    saved = pyqtSignal(str)
    failed = pyqtSignal(str)
    busyChanged = pyqtSignal(bool)

    def __init__(self, parent: QObject | None = None) -> None:
        super().__init__(parent)
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

    def start_work(self, work: Work) -> int:
        """Run `work` in the background; returns the job's serial."""
        self._abandon()
        self._serial += 1
        self._stop = threading.Event()
        self._pool.start(_Task(self._serial, work, self._signals, self._stop))
        self.busyChanged.emit(True)
        return self._serial

    def cancel(self) -> bool:
        """Stop the running job (at its next progress report)."""
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
        """Stop the running job and wait for its thread (renderers are released there)."""
        self._abandon()
        self._serial += 1
        return self._pool.waitForDone(timeout_ms)
