"""Loading files off the GUI thread: newest request wins, and a load can be abandoned.

Readers can take seconds on real datasets (DICOM series, large meshes), and the window must keep
painting and answering meanwhile. `Loader.start` runs `core.loading.load_input` on a thread pool and
reports back through queued signals: the stage it is in (`stageChanged`), then `loaded` or
`failed`. A result that is no longer the newest request (the person opened something else, or
cancelled) is dropped, so the window keeps what it showed.

A reader cannot be interrupted halfway through a file, so cancelling is cooperative: the load's
progress callback raises `LoadCancelled` at the next stage, which skips the rest of the work
(the mesh preparation after a read, say); the result of a stage already running is thrown away.
Load functions that take no `progress` argument (test doubles) still work; they are only
abandoned, not stopped.
"""

from __future__ import annotations

import inspect
import threading
from collections.abc import Callable, Mapping
from typing import Any

from PyQt5.QtCore import QObject, QRunnable, QThreadPool, pyqtSignal, pyqtSlot

from volren.app.core.loading import LoadCancelled, LoadedInput, PathArg, load_input, one_line_error

#: load(path, tf, scalars) or load(path, tf, scalars, progress=...) -> LoadedInput.
LoadFunction = Callable[..., LoadedInput]


def _takes_progress(load: LoadFunction) -> bool:
    try:
        parameters = inspect.signature(load).parameters.values()
    except (TypeError, ValueError):  # builtins and odd callables: call them the plain way
        return False
    return any(p.name == "progress" or p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters)


class _Signals(QObject):
    """Lives in the GUI thread; emitting from the pool thread queues the call."""

    done = pyqtSignal(int, object)
    failed = pyqtSignal(int, str)
    stage = pyqtSignal(int, str, object)  # serial, text, fraction or None


class _LoadTask(QRunnable):
    def __init__(
        self,
        serial: int,
        signals: _Signals,
        load: LoadFunction,
        args: tuple,
        pass_progress: bool,
        cancelled: threading.Event,
    ) -> None:
        super().__init__()
        self._serial = serial
        self._signals = signals
        self._load = load
        self._args = args
        self._pass_progress = pass_progress
        self.cancelled = cancelled

    def _progress(self, stage: str, fraction: float | None = None) -> None:
        if self.cancelled.is_set():
            raise LoadCancelled()
        self._emit("stage", stage, fraction)

    def run(self) -> None:
        try:
            if self._pass_progress:
                result = self._load(*self._args, progress=self._progress)
            else:
                result = self._load(*self._args)
        except LoadCancelled:
            return
        except BaseException as exc:  # noqa: BLE001 - every failure becomes a message
            if not self.cancelled.is_set():
                self._emit("failed", one_line_error(exc, self._args[0]))
        else:
            if not self.cancelled.is_set():
                self._emit("done", result)

    def _emit(self, signal: str, *payload: object) -> None:
        try:
            getattr(self._signals, signal).emit(self._serial, *payload)
        except RuntimeError:  # the window closed (and its signals object went) while we loaded
            pass


class Loader(QObject):
    """Start loads; `loaded(result, context)` or `failed(message, context)` for the newest one.

    `cancel()` abandons the running load (`cancelled(context)` says so); `start` while one runs
    abandons the old one silently, the new one speaks for both.
    """

    loaded = pyqtSignal(object, object)  # LoadedInput, the context given to start()
    failed = pyqtSignal(str, object)  # one-line message, context
    cancelled = pyqtSignal(object)  # context of the abandoned load
    busyChanged = pyqtSignal(bool)
    stageChanged = pyqtSignal(str, object)  # "Reading bonsai.vti…", fraction done or None

    def __init__(self, parent: QObject | None = None, load: LoadFunction = load_input) -> None:
        super().__init__(parent)
        self._load = load
        self._pass_progress = _takes_progress(load)
        self._pool = QThreadPool(self)
        # Abandoned loads may still be inside a reader: leave room for the newest beside them.
        self._pool.setMaxThreadCount(3)
        self._signals = _Signals(self)
        self._signals.done.connect(self._on_done)
        self._signals.failed.connect(self._on_failed)
        self._signals.stage.connect(self._on_stage)
        self._serial = 0
        self._cancel_running: threading.Event | None = None  # set: the running load stops
        self._context: Any = None
        self._busy = False

    @property
    def busy(self) -> bool:
        return self._busy

    def start(
        self,
        path: PathArg | None = None,
        tf: PathArg | None = None,
        scalars: str | None = None,
        context: Any = None,
        raw: Mapping[str, Any] | None = None,
    ) -> int:
        """Load in the background (abandoning any load still running); returns the load's serial."""
        self._abandon()
        self._serial += 1
        self._context = context
        # The pool owns (and deletes) the task; only its cancel flag is kept here.
        self._cancel_running = threading.Event()
        task = _LoadTask(
            self._serial,
            self._signals,
            self._load,
            (path, tf, scalars) if raw is None else (path, tf, scalars, raw),
            self._pass_progress,
            self._cancel_running,
        )
        self._set_busy(True)
        self._pool.start(task)
        return self._serial

    def cancel(self) -> bool:
        """Abandon the running load: its result will be dropped. False when none was running."""
        if not self._busy:
            return False
        context = self._context
        self._abandon()
        self._serial += 1  # whatever the abandoned task still sends is stale now
        self._set_busy(False)
        self.cancelled.emit(context)
        return True

    def _abandon(self) -> None:
        if self._cancel_running is not None:
            self._cancel_running.set()
            self._cancel_running = None

    @pyqtSlot(int, object)
    def _on_done(self, serial: int, result: LoadedInput) -> None:
        if serial == self._serial and self._busy:
            self._finish()
            self.loaded.emit(result, self._context)

    @pyqtSlot(int, str)
    def _on_failed(self, serial: int, message: str) -> None:
        if serial == self._serial and self._busy:
            self._finish()
            self.failed.emit(message, self._context)

    @pyqtSlot(int, str, object)
    def _on_stage(self, serial: int, text: str, fraction: object) -> None:
        if serial == self._serial and self._busy:
            self.stageChanged.emit(text, fraction)

    def _finish(self) -> None:
        self._cancel_running = None
        self._set_busy(False)

    def _set_busy(self, busy: bool) -> None:
        if busy != self._busy:
            self._busy = busy
            self.busyChanged.emit(busy)

    def wait(self, timeout_ms: int) -> bool:
        """Wait for running loads (used when the window closes)."""
        return self._pool.waitForDone(timeout_ms)

    def shutdown(self, timeout_ms: int = 5000) -> bool:
        """Stop the running load at its next stage and wait for the pool; nothing is emitted."""
        self._abandon()
        self._serial += 1
        return self.wait(timeout_ms)
