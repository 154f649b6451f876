"""Loading files off the GUI thread, newest request wins.

Readers can take seconds on real datasets (DICOM series, large meshes), and the window must keep
painting and answering meanwhile. `Loader.start` runs `loading.load_input` on a thread pool and
reports back through queued signals; a result that is no longer the newest request (the person
opened something else meanwhile) is dropped.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from PyQt5.QtCore import QObject, QRunnable, QThreadPool, pyqtSignal, pyqtSlot

from volren.app.loading import LoadedInput, PathArg, load_input, one_line_error

LoadFunction = Callable[[PathArg | None, PathArg | None, str | None], LoadedInput]


class _Signals(QObject):
    """Lives in the GUI thread; emitting from the pool thread queues the call."""

    done = pyqtSignal(int, object)
    failed = pyqtSignal(int, str)


class _LoadTask(QRunnable):
    def __init__(self, serial: int, signals: _Signals, load: LoadFunction, args: tuple) -> None:
        super().__init__()
        self._serial = serial
        self._signals = signals
        self._load = load
        self._args = args

    def run(self) -> None:
        try:
            result = self._load(*self._args)
        except BaseException as exc:  # noqa: BLE001 - every failure becomes a message
            self._emit("failed", one_line_error(exc, self._args[0]))
        else:
            self._emit("done", result)

    def _emit(self, signal: str, payload: object) -> None:
        try:
            getattr(self._signals, signal).emit(self._serial, payload)
        except RuntimeError:  # the window closed (and its signals object went) while we loaded
            pass


class Loader(QObject):
    """Start loads; `loaded(result, context)` or `failed(message, context)` for the newest one."""

    loaded = pyqtSignal(object, object)  # LoadedInput, the context given to start()
    failed = pyqtSignal(str, object)  # one-line message, context
    busyChanged = pyqtSignal(bool)

    def __init__(self, parent: QObject | None = None, load: LoadFunction = load_input) -> None:
        super().__init__(parent)
        self._load = load
        self._pool = QThreadPool(self)
        self._pool.setMaxThreadCount(2)
        self._signals = _Signals(self)
        self._signals.done.connect(self._on_done)
        self._signals.failed.connect(self._on_failed)
        self._serial = 0
        self._context: Any = None
        self._busy = False

    @property
    def busy(self) -> bool:
        return self._busy

    def start(
        self, path: PathArg | None = None, tf: PathArg | None = None, scalars: str | None = None, context: Any = None
    ) -> int:
        self._serial += 1
        self._context = context
        self._set_busy(True)
        self._pool.start(_LoadTask(self._serial, self._signals, self._load, (path, tf, scalars)))
        return self._serial

    @pyqtSlot(int, object)
    def _on_done(self, serial: int, result: LoadedInput) -> None:
        if serial == self._serial:
            self._set_busy(False)
            self.loaded.emit(result, self._context)

    @pyqtSlot(int, str)
    def _on_failed(self, serial: int, message: str) -> None:
        if serial == self._serial:
            self._set_busy(False)
            self.failed.emit(message, self._context)

    def _set_busy(self, busy: bool) -> None:
        if busy != self._busy:
            self._busy = busy
            self.busyChanged.emit(busy)

    def wait(self, timeout_ms: int) -> bool:
        """Wait for running loads (used when the window closes)."""
        return self._pool.waitForDone(timeout_ms)
