"""The chunk cache: never more than its budget, least recently used out first, read-only copies
equal to what was loaded, and a chunk larger than the budget handed out without being kept."""

from __future__ import annotations

import numpy as np
import pytest

from volren.bricked.chunk_cache import ChunkCache


def test_the_cache_keeps_its_budget_and_evicts_the_least_recently_used():
    cache = ChunkCache(3 * 800)
    loads: list[int] = []

    def chunk(n):
        def load():
            loads.append(n)
            return np.full((10, 10), n, dtype=np.float64)  # 800 bytes

        return load

    for n in (1, 2, 3):
        assert cache.get(n, chunk(n))[0, 0] == n
    cache.get(1, chunk(1))  # 1 is now the most recent
    cache.get(4, chunk(4))  # evicts 2, the least recently used
    assert loads == [1, 2, 3, 4] and len(cache) == 3
    cache.get(2, chunk(2))
    assert loads[-1] == 2 and cache.stats.evictions == 2
    assert cache.stats.held_bytes <= 3 * 800 and cache.stats.peak_bytes <= 3 * 800
    assert cache.stats.hits == 1 and cache.stats.misses == 5
    held = cache.get(2, chunk(2))
    np.testing.assert_array_equal(held, np.full((10, 10), 2.0))
    with pytest.raises(ValueError):
        held[0, 0] = 7.0  # the cache's copy is read-only


def test_a_chunk_larger_than_the_budget_is_not_kept():
    cache = ChunkCache(100)
    big = cache.get("big", lambda: np.ones(1000, dtype=np.uint8))
    assert big.sum() == 1000 and len(cache) == 0 and cache.stats.held_bytes == 0
