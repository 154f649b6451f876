"""The volumes of a time series' steps, read off the GUI thread, neighbours ahead of time.

Stepping through time must not wait on the reader each time: the step asked for is read first,
then the steps beside it (the next one first, where playback goes), each prepared for rendering
as a loaded file is (histograms, a mesh's preparation: `core.loading.prepare_for_rendering`), so
moving one step on shows a volume already in memory. `CACHED_STEPS` volumes are kept, the least
recently shown dropped first. The newest request wins: a step asked for while another is read
comes next, and steps no longer near the one shown are not read at all.
"""

from __future__ import annotations

import functools
from collections import OrderedDict
from collections.abc import Callable
from pathlib import Path

from PyQt5.QtCore import QObject, pyqtSignal, pyqtSlot

from volren.app.core.loading import prepare_for_rendering
from volren.app.files.pool_read import SerialReads
from volren.io.series_io import TimeSeries
from volren.model.volume import Volume

#: Steps kept in memory: the one shown and its two neighbours.
CACHED_STEPS = 3

#: read(step file, scalars) -> the step's volume, prepared for rendering.
StepReader = Callable[[Path, str | None], Volume]


def read_step(path: Path, scalars: str | None) -> Volume:
    from volren.io import load_volume

    volume = load_volume(path, scalars=scalars)
    prepare_for_rendering(volume)
    return volume


class SeriesSteps(QObject):
    """`request(index)` answers `stepReady(index, volume)` (at once for a step in memory) or
    `stepFailed(index, message)`, for the newest request only."""

    stepReady = pyqtSignal(int, object)
    stepFailed = pyqtSignal(int, str)

    def __init__(self, series: TimeSeries, scalars: str | None = None, read: StepReader = read_step,
                 parent: QObject | None = None) -> None:  # fmt: skip
        super().__init__(parent)
        self.series = series
        self._scalars = scalars
        self._read = read
        self._cache: OrderedDict[int, Volume] = OrderedDict()
        self._queue: list[int] = []
        self._reading: int | None = None
        self._wanted: int | None = None
        self._reads = SerialReads(self, self._on_done, self._on_failed)

    @property
    def cached(self) -> tuple[int, ...]:
        """The steps in memory, least recently shown first."""
        return tuple(self._cache)

    @property
    def reading(self) -> int | None:
        """The step being read now, if any."""
        return self._reading

    def keep(self, index: int, volume: Volume) -> None:
        """A step read elsewhere (the first one, opened as a file): kept, neighbours read ahead."""
        self._store(index, volume)
        self._wanted = index
        self._read_ahead(index)

    def request(self, index: int) -> None:
        """Ask for step `index`; its answer comes as a signal (now, if it is in memory)."""
        if not 0 <= index < len(self.series):
            raise IndexError(f"no step {index}: the series has {len(self.series)}")
        self._wanted = index
        if index in self._cache:
            self._cache.move_to_end(index)
            self.stepReady.emit(index, self._cache[index])
            self._read_ahead(index)
            return
        self._queue = [index] + self._neighbours(index)
        self._pump()

    def _neighbours(self, index: int) -> list[int]:
        near = [i for i in (index + 1, index - 1) if 0 <= i < len(self.series)]
        return [i for i in near if i not in self._cache and i != self._reading]

    def _read_ahead(self, index: int) -> None:
        self._queue = self._neighbours(index)
        self._pump()

    def _pump(self) -> None:
        while self._reading is None and self._queue:
            index = self._queue.pop(0)
            if index in self._cache:
                continue
            self._reading = index
            path = self.series.steps[index]
            read = functools.partial(self._read, path, self._scalars)
            self._reads.start(index, path, read)

    def _store(self, index: int, volume: Volume) -> None:
        self._cache[index] = volume
        self._cache.move_to_end(index)
        while len(self._cache) > CACHED_STEPS:
            oldest = next(iter(self._cache))
            if oldest == self._wanted:  # never drop the step shown
                self._cache.move_to_end(oldest)
                oldest = next(iter(self._cache))
            del self._cache[oldest]

    @pyqtSlot(object, object)
    def _on_done(self, index: int, volume: object) -> None:
        self._reading = None
        wanted = index == self._wanted
        if wanted or self._wanted is None or abs(index - self._wanted) <= 1:  # far steps: not worth memory
            self._store(index, volume)  # type: ignore[arg-type]
        if wanted:
            self.stepReady.emit(index, volume)
            self._read_ahead(index)
        else:
            self._pump()

    @pyqtSlot(object, str)
    def _on_failed(self, index: int, message: str) -> None:
        self._reading = None
        if index == self._wanted:
            self.stepFailed.emit(index, message)
        self._pump()

    def shutdown(self, timeout_ms: int = 30000) -> bool:
        """Read nothing more and wait for the read in progress."""
        self._queue = []
        return self._reads.wait(timeout_ms)
