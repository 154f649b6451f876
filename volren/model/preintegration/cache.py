"""A bounded, thread-safe cache of pre-integration tables.

Why: renderers ask for the table on every frame, but it only changes when the TF, the table size,
the segment length(s) or the value range change. Keys hold the TF's `version` (unique across all
TF instances and bumped by every edit), never the TF itself, so nothing is kept alive.

Least recently used tables are evicted once the total exceeds `max_bytes`; a table larger than
the whole budget is computed and returned but not kept. Cached arrays are read-only, so a caller
cannot corrupt what the next caller gets. Computation happens under the lock: two threads asking
for the same table compute it once (and numba's parallel kernels are not run concurrently).
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable
from typing import TypeVar

import numpy as np

T = TypeVar("T")

#: Default budget: four 4096^2 float32 RGBA tables, or thousands of 256^2 ones.
DEFAULT_MAX_BYTES = 1 << 30


def _nbytes(value: object) -> int:
    if isinstance(value, np.ndarray):
        return int(value.nbytes)
    return sum(_nbytes(v) for v in getattr(value, "arrays", ()))


def _freeze(value: object) -> None:
    if isinstance(value, np.ndarray):
        value.flags.writeable = False
    for v in getattr(value, "arrays", ()):
        _freeze(v)


class TableCache:
    """LRU cache of arrays (or objects exposing their arrays as `.arrays`) bounded in bytes."""

    def __init__(self, max_bytes: int = DEFAULT_MAX_BYTES) -> None:
        if max_bytes < 0:
            raise ValueError(f"max_bytes must be >= 0, got {max_bytes}")
        self.max_bytes = int(max_bytes)
        self._items: OrderedDict[Hashable, tuple[object, int]] = OrderedDict()
        self._bytes = 0
        self._lock = threading.RLock()
        self.hits = 0
        self.misses = 0

    @property
    def nbytes(self) -> int:
        """Bytes held now (at most `max_bytes`)."""
        return self._bytes

    def __len__(self) -> int:
        return len(self._items)

    def __contains__(self, key: Hashable) -> bool:
        return key in self._items

    def get_or_compute(self, key: Hashable, compute: Callable[[], T]) -> T:
        """The cached value for `key`, or `compute()` stored (read-only) under it."""
        with self._lock:
            found = self._items.get(key)
            if found is not None:
                self._items.move_to_end(key)
                self.hits += 1
                return found[0]  # type: ignore[return-value]
            self.misses += 1
            value = compute()
            _freeze(value)
            size = _nbytes(value)
            if size <= self.max_bytes:
                self._items[key] = (value, size)
                self._bytes += size
                while self._bytes > self.max_bytes:
                    _, (_, dropped) = self._items.popitem(last=False)
                    self._bytes -= dropped
            return value

    def clear(self) -> None:
        """Drop every table and start the hit/miss counts afresh."""
        with self._lock:
            self._items.clear()
            self._bytes = 0
            self.hits = 0
            self.misses = 0
