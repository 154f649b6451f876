"""Reading a volume on a pool thread and answering in the GUI thread, keyed by who asked.

Why one task for every background read of a volume (time steps, OME-Zarr levels): the read must
never throw into Qt's thread pool, every failure must come back as one line naming the file, and
a window closed while the read runs must not crash the emit.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from PyQt5.QtCore import QObject, QRunnable, QThreadPool, pyqtSignal

from volren.app.core.loading import one_line_error


class ReadSignals(QObject):
    """Lives in the GUI thread; emitting from the pool thread queues the call.
    done(key, volume) and failed(key, one-line message)."""

    done = pyqtSignal(object, object)
    failed = pyqtSignal(object, str)


class ReadTask(QRunnable):
    """`read()` on a pool thread; its volume or its failure (naming `source`) reported under `key`."""

    def __init__(
        self, key: object, source: str | Path, read: Callable[[], object], signals: ReadSignals
    ) -> None:
        super().__init__()
        self._key, self._source, self._read, self._signals = key, source, read, signals

    def run(self) -> None:
        try:
            volume = self._read()
        except BaseException as exc:  # noqa: BLE001 - every failure becomes a one-line message
            self._emit("failed", one_line_error(exc, self._source))
            return
        self._emit("done", volume)

    def _emit(self, signal: str, payload: object) -> None:
        try:
            getattr(self._signals, signal).emit(self._key, payload)
        except RuntimeError:  # the window closed while we read
            pass


class SerialReads(QObject):
    """Reads one at a time, in the order started, on a pool thread of their own (the callers'
    queues, coarse level before fine, the step shown before its neighbours, rely on that order);
    each answered in the GUI thread by `done(key, volume)` or `failed(key, one-line message)`."""

    def __init__(
        self, parent: QObject, done: Callable[[Any, object], None], failed: Callable[[Any, str], None]
    ) -> None:
        super().__init__(parent)
        self._pool = QThreadPool(self)
        self._pool.setMaxThreadCount(1)
        self._signals = ReadSignals(self)
        self._signals.done.connect(done)
        self._signals.failed.connect(failed)

    def start(self, key: object, source: str | Path, read: Callable[[], object]) -> None:
        """Queue `read()` (its failures named after `source`), answered under `key`."""
        self._pool.start(ReadTask(key, source, read, self._signals))

    def wait(self, timeout_ms: int) -> bool:
        """Wait for the reads under way and queued; False when `timeout_ms` passed first."""
        return self._pool.waitForDone(timeout_ms)
