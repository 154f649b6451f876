"""The decompressed bricks (chunks) of a level held in memory, least recently used first out.

Why: a render brick reads its own chunk and thin slabs of its neighbours' (ghost voxels), and
bricks are visited in visibility order, so the same chunk is wanted several times within a frame
and again in the next; reading it from disk (or a server) and decompressing it each time would
cost more than rendering it. The cache never holds more than its budget of bytes (a chunk larger
than the whole budget is handed out without being kept).
"""

from __future__ import annotations

import mmap
from collections import OrderedDict
from collections.abc import Callable, Hashable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from volren.heap import release_free_heap


@dataclass
class CacheStats:
    hits: int = 0
    misses: int = 0
    evictions: int = 0
    held_bytes: int = 0
    peak_bytes: int = 0


class ChunkCache:
    """At most `budget` bytes of arrays, keyed by chunk, evicted least recently used first."""

    def __init__(self, budget: int) -> None:
        self.budget = int(budget)
        self._items: OrderedDict[Hashable, NDArray] = OrderedDict()
        self.stats = CacheStats()

    def get(self, key: Hashable, load: Callable[[], NDArray]) -> NDArray:
        """The array under `key`, loaded (and kept, evicting others as needed) on a miss."""
        found = self._items.get(key)
        if found is not None:
            self._items.move_to_end(key)
            self.stats.hits += 1
            return found
        self.stats.misses += 1
        if self.stats.misses % TRIM_EVERY == 0:
            release_free_heap()
        value = np.asarray(load())
        if value.nbytes > self.budget:
            return value
        while self._items and self.stats.held_bytes + value.nbytes > self.budget:
            _, old = self._items.popitem(last=False)
            self.stats.held_bytes -= old.nbytes
            self.stats.evictions += 1
        value = _outside_the_heap(value)
        self._items[key] = value
        self.stats.held_bytes += value.nbytes
        self.stats.peak_bytes = max(self.stats.peak_bytes, self.stats.held_bytes)
        return value

    def __len__(self) -> int:
        return len(self._items)

    def clear(self) -> None:
        self._items.clear()
        self.stats.held_bytes = 0


#: Misses between two `release_free_heap` calls.
TRIM_EVERY = 32


def _outside_the_heap(value: NDArray) -> NDArray:
    """A read-only copy of `value` in its own anonymous memory map, returned to the system the
    moment it is evicted.

    Why: chunks held in malloc's heap and evicted in LRU order fragment it, and a fragmented heap
    does not shrink: a process streaming 1024^3 uint16 through a 2 GiB cache grew to 3.4 GiB.
    (Making malloc map every large block instead kept it at 2.1 GiB but slowed every brick's
    texture upload by half; only the cache needs it.)"""
    if value.nbytes == 0:
        return value
    buffer = mmap.mmap(-1, value.nbytes)
    copy = np.frombuffer(buffer, dtype=value.dtype).reshape(value.shape)
    copy[...] = value
    copy.flags.writeable = False
    return copy
