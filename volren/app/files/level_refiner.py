"""An OME-Zarr image opens at its coarsest level at once and is refined level by level in the
background, each finer level shown as it arrives (TF, camera and settings kept), up to the finest
that fits in memory: the person sees the data in a moment instead of after the whole read.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence

from PyQt5.QtCore import QObject, pyqtSignal, pyqtSlot

from volren.app.core.loading import prepare_for_rendering
from volren.app.files.pool_read import SerialReads
from volren.model.volume import Volume

#: read(path, level) -> that level, prepared for rendering.
LevelReader = Callable[[str, int], Volume]


def read_level(path: str, level: int) -> Volume:
    from volren.io import load_volume

    volume = load_volume(path, level=level)
    prepare_for_rendering(volume)
    return volume


class LevelRefiner(QObject):
    """`start(path, levels)` reads `levels` (coarse to fine) one after the other and emits
    `levelReady(level, volume)` for each; `cancel()` (or a new start) drops what is under way."""

    levelReady = pyqtSignal(int, object)
    failed = pyqtSignal(str)

    def __init__(self, read: LevelReader = read_level, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._read = read
        self._serial = 0
        self._path = ""
        self._levels: list[int] = []
        self._reads = SerialReads(self, self._on_done, self._on_failed)

    @property
    def pending(self) -> tuple[int, ...]:
        """The levels still to come, the one being read first."""
        return tuple(self._levels)

    def start(self, path: str, levels: Sequence[int]) -> None:
        self.cancel()
        self._path, self._levels = str(path), list(levels)
        self._next()

    def cancel(self) -> None:
        self._serial += 1
        self._levels = []

    def _next(self) -> None:
        if self._levels:
            path, level = self._path, self._levels[0]
            read = functools.partial(self._read, path, level)
            self._reads.start((self._serial, level), path, read)

    @pyqtSlot(object, object)
    def _on_done(self, key: tuple[int, int], volume: object) -> None:
        serial, level = key
        if serial != self._serial:
            return
        self._levels.pop(0)
        self.levelReady.emit(level, volume)
        self._next()

    @pyqtSlot(object, str)
    def _on_failed(self, key: tuple[int, int], message: str) -> None:
        if key[0] == self._serial:
            self._levels = []
            self.failed.emit(message)

    def shutdown(self, timeout_ms: int = 30000) -> bool:
        self.cancel()
        return self._reads.wait(timeout_ms)
