"""The 1D editor's value histogram, computed in a pool thread for large volumes.

Why: the histogram of a 256^3 grid (16.7 million values) took 0.15-0.85 s on the GUI thread each
time a volume was opened, during which the window answered nothing. numpy's tallies release the
interpreter's lock, so in a pool thread they cost the window nothing; the plot shows the TF at
once and its histogram when it is ready. Small volumes keep theirs at once (no empty plot first).
"""

from __future__ import annotations

from PyQt5.QtCore import QObject, QRunnable, QThreadPool, pyqtSignal

from volren.model.value_histogram import Histogram, cached_value_histogram, value_histogram
from volren.model.volume import Volume

#: Volumes with more values than this get their histogram in the background (about 15 ms of work).
BACKGROUND_VALUES = 2_000_000


class _Signals(QObject):
    done = pyqtSignal(int, object, object)  # serial, volume, histogram


class _Task(QRunnable):
    def __init__(self, serial: int, volume: Volume, signals: _Signals) -> None:
        super().__init__()
        self._serial, self._volume, self._signals = serial, volume, signals

    def run(self) -> None:
        histogram = value_histogram(self._volume)
        try:
            self._signals.done.emit(self._serial, self._volume, histogram)
        except RuntimeError:  # the window closed meanwhile
            pass


class BackgroundHistogram(QObject):
    """`request(volume)` gives the histogram now (small or already computed) or later through
    `ready(volume, histogram)`; only the newest request is answered."""

    ready = pyqtSignal(object, object)

    def __init__(self, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._pool = QThreadPool(self)
        self._pool.setMaxThreadCount(1)
        self._signals = _Signals(self)
        self._signals.done.connect(self._on_done)
        self._serial = 0

    def request(self, volume: Volume) -> Histogram | None:
        """The histogram of `volume` if it is at hand now, else None and `ready` later."""
        self._serial += 1
        found = cached_value_histogram(volume)
        if found is not None or volume.values.size <= BACKGROUND_VALUES:
            return found if found is not None else value_histogram(volume)
        self._pool.start(_Task(self._serial, volume, self._signals))
        return None

    def wait(self, msecs: int = 30_000) -> bool:
        """Block until the pool is idle (tests, shutdown)."""
        return bool(self._pool.waitForDone(msecs))

    def _on_done(self, serial: int, volume: Volume, histogram: Histogram) -> None:
        if serial == self._serial:
            self.ready.emit(volume, histogram)
