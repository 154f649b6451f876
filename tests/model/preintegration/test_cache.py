"""The pre-integration table cache: hits return the very same read-only object, every input the
table depends on is part of the key, memory stays within its byte budget (LRU), and concurrent
requests compute a table once. No timings here: speed is measured by `python -m benchmarks.preint`."""

from __future__ import annotations

import gc
import threading
import time
import weakref
from collections import OrderedDict

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.model.preintegration.tfs import smooth, spiky
from volren.model.preintegration import (
    TABLE_CACHE,
    LightingTables,
    TableCache,
    lighting_tables,
    preintegrate,
)
from volren.model.preintegration import tables as tables_module

STABLE = settings(derandomize=True, database=None, deadline=None, max_examples=200)

#: Bytes of one float32 RGBA 2D table of size 8.
N8_BYTES = 8 * 8 * 4 * 4


@pytest.fixture(autouse=True)
def empty_module_cache():
    """Each test starts and ends with an empty module-level cache, so tests cannot interact."""
    TABLE_CACHE.clear()
    yield
    TABLE_CACHE.clear()


@pytest.fixture
def computations(monkeypatch) -> list[tuple]:
    """Counts real table computations: every call of `tables._exact_tables` appends its arguments."""
    calls: list[tuple] = []
    original = tables_module._exact_tables

    def counting(tf, spec, weighted, brute_force=False):
        calls.append((tf.version, spec, weighted, brute_force))
        return original(tf, spec, weighted, brute_force)

    monkeypatch.setattr(tables_module, "_exact_tables", counting)
    return calls


# ----------------------------------------------------------------------------------- hits
def test_second_identical_request_is_the_same_object_without_recomputation(computations):
    """A renderer asks every frame; the second request must cost a lookup, not a table."""
    cache = TableCache()
    tf = spiky()
    first = preintegrate(tf, 8, step=0.5, cache=cache)
    second = preintegrate(tf, 8, step=0.5, cache=cache)
    assert second is first
    assert (cache.hits, cache.misses) == (1, 1)
    assert len(computations) == 1 and len(cache) == 1
    np.testing.assert_array_equal(first, preintegrate(tf, 8, step=0.5, cache=None))


def test_second_identical_lighting_request_is_the_same_object(computations):
    """Lighting tables are cached as one object holding both arrays."""
    cache = TableCache()
    tf = spiky()
    first = lighting_tables(tf, 8, step=0.5, cache=cache)
    second = lighting_tables(tf, 8, step=0.5, cache=cache)
    assert isinstance(first, LightingTables) and second is first
    assert (cache.hits, cache.misses) == (1, 1) and len(computations) == 1
    assert cache.nbytes == 2 * N8_BYTES  # both arrays are counted


def test_equivalent_spellings_of_a_request_share_one_entry(computations):
    """Defaults resolved to the same values (oversampling=None, lengths as list or array) hit."""
    cache = TableCache()
    tf = smooth()
    a = preintegrate(tf, 8, step=0.5, cache=cache)
    auto = -(-(tables_module.AUTO_MIN_ENTRIES - 1) // 7)
    b = preintegrate(tf, 8, step=0.5, oversampling=auto, value_range=tf.value_range, cache=cache)
    c = preintegrate(tf, 8, lengths=[0.25, 0.5], cache=cache)
    d = preintegrate(tf, 8, lengths=np.array([0.25, 0.5]), cache=cache)
    assert b is a and d is c
    assert (cache.hits, cache.misses) == (2, 2) and len(computations) == 2


def test_default_cache_is_the_module_table_cache(computations):
    """Without cache= both functions use TABLE_CACHE; cache=None bypasses it."""
    tf = smooth()
    plain = preintegrate(tf, 8, step=0.5)
    assert preintegrate(tf, 8, step=0.5) is plain
    light = lighting_tables(tf, 8, step=0.5)
    assert lighting_tables(tf, 8, step=0.5) is light
    assert (TABLE_CACHE.hits, TABLE_CACHE.misses) == (2, 2) and len(TABLE_CACHE) == 2
    uncached = preintegrate(tf, 8, step=0.5, cache=None)
    assert uncached is not plain and len(TABLE_CACHE) == 2 and len(computations) == 3
    np.testing.assert_array_equal(uncached, plain)


# ---------------------------------------------------------------------------------- misses
@pytest.mark.parametrize(
    "edit",
    [
        lambda tf: tf.set_opacity_points([[0, 0.1], [1, 0.9]]),
        lambda tf: tf.set_color_points([[0, 0, 0, 1], [1, 1, 1, 0]]),
        lambda tf: tf.set_opacity_unit_distance(0.25),
        lambda tf: tf.rescale(0.0, 2.0),
    ],
    ids=["opacity", "colour", "unit-distance", "rescale"],
)
def test_editing_the_tf_gives_a_miss_and_the_new_table(edit, computations):
    """A stale table after a TF edit would render the old TF: every edit must change the key."""
    cache = TableCache()
    tf = smooth()
    before = preintegrate(tf, 8, step=0.5, value_range=(0.0, 1.0), cache=cache)
    edit(tf)
    after = preintegrate(tf, 8, step=0.5, value_range=(0.0, 1.0), cache=cache)
    assert after is not before and cache.misses == 2 and cache.hits == 0 and len(computations) == 2
    assert not np.array_equal(after, before)
    np.testing.assert_array_equal(after, preintegrate(tf, 8, step=0.5, value_range=(0.0, 1.0), cache=None))


BASE = dict(n=8, step=0.5)


@pytest.mark.parametrize(
    "change",
    [
        dict(n=9),
        dict(step=0.7),
        dict(step=None, lengths=[0.5, 1.0]),
        dict(value_range=(0.0, 2.0)),
        dict(value_range=(-0.5, 1.0)),
        dict(oversampling=1),
        dict(oversampling=3),
    ],
    ids=["n", "step", "lengths", "range-hi", "range-lo", "oversampling-1", "oversampling-3"],
)
@pytest.mark.parametrize("function", [preintegrate, lighting_tables])
def test_changing_any_table_input_gives_a_miss_and_a_different_table(function, change, computations):
    """n, step, lengths, value range and oversampling all change the table, so all are in the key."""
    cache = TableCache()
    tf = spiky()
    base = function(tf, cache=cache, **BASE)
    other = function(tf, cache=cache, **{**BASE, **change})
    assert other is not base and cache.misses == 2 and cache.hits == 0 and len(computations) == 2
    assert len(cache) == 2
    expected = function(tf, cache=None, **{**BASE, **change})
    for got, want, old in zip(_arrays(other), _arrays(expected), _arrays(base)):
        np.testing.assert_array_equal(got, want)
        assert got.shape != old.shape or not np.array_equal(got, old)


def _arrays(value) -> tuple[np.ndarray, ...]:
    return value.arrays if isinstance(value, LightingTables) else (value,)


@pytest.mark.parametrize("function", [preintegrate, lighting_tables])
def test_a_2d_table_and_a_one_length_3d_table_are_different_entries(function):
    """step=L gives (n, n, 4) and lengths=[L] gives (1, n, n, 4): a hit must not return the other shape."""
    cache = TableCache()
    tf = smooth()
    flat = function(tf, 8, step=0.5, cache=cache)
    layered = function(tf, 8, lengths=[0.5], cache=cache)
    assert all(a.shape == (8, 8, 4) for a in _arrays(flat))
    assert all(a.shape == (1, 8, 8, 4) for a in _arrays(layered)), [a.shape for a in _arrays(layered)]
    # and in the other order
    cache.clear()
    layered = function(tf, 8, lengths=[0.5], cache=cache)
    flat = function(tf, 8, step=0.5, cache=cache)
    assert all(a.shape == (8, 8, 4) for a in _arrays(flat)), [a.shape for a in _arrays(flat)]


def test_plain_and_lighting_tables_of_one_spec_are_different_keys(computations):
    """Same TF and spec, different kinds of table: neither request may return the other's result."""
    cache = TableCache()
    tf = spiky()
    plain = preintegrate(tf, 8, step=0.5, cache=cache)
    light = lighting_tables(tf, 8, step=0.5, cache=cache)
    assert isinstance(plain, np.ndarray) and isinstance(light, LightingTables)
    assert cache.misses == 2 and cache.hits == 0 and len(cache) == 2 and len(computations) == 2
    assert preintegrate(tf, 8, step=0.5, cache=cache) is plain
    assert lighting_tables(tf, 8, step=0.5, cache=cache) is light
    # opacity agrees; the plain colour splits into the front and back diffuse parts
    np.testing.assert_array_equal(light.opacity, plain[..., 3])
    np.testing.assert_allclose(light.diffuse_front + light.diffuse_back, plain[..., :3], atol=2e-7)


def test_equal_tfs_with_different_versions_are_separate_correct_entries(computations):
    """Keys use the version, not the contents: two equal TFs get two entries, each its own TF's
    table, and editing one never changes what the other gets."""
    cache = TableCache()
    a, b = smooth(), smooth()
    assert a == b and a.version != b.version
    table_a = preintegrate(a, 8, step=0.5, cache=cache)
    table_b = preintegrate(b, 8, step=0.5, cache=cache)
    assert table_b is not table_a and len(cache) == 2 and cache.misses == 2
    np.testing.assert_array_equal(table_a, table_b)
    b.set_opacity_points([[0, 1.0]])
    table_b2 = preintegrate(b, 8, step=0.5, cache=cache)
    assert preintegrate(a, 8, step=0.5, cache=cache) is table_a
    np.testing.assert_array_equal(table_a, preintegrate(a, 8, step=0.5, cache=None))
    np.testing.assert_array_equal(table_b2, preintegrate(b, 8, step=0.5, cache=None))
    assert not np.array_equal(table_b2, table_a)
    copy = a.copy()
    assert preintegrate(copy, 8, step=0.5, cache=cache) is not table_a  # a copy has its own version


def test_cache_does_not_keep_the_tf_alive():
    """Keys hold the TF's version, not the TF: a dropped TF can be garbage-collected."""
    cache = TableCache()
    tf = smooth()
    ref = weakref.ref(tf)
    preintegrate(tf, 8, step=0.5, cache=cache)
    lighting_tables(tf, 8, step=0.5, cache=cache)
    del tf
    gc.collect()
    assert ref() is None and len(cache) == 2


# ------------------------------------------------------------------------------- read-only
def test_cached_plain_tables_are_read_only():
    """Cached arrays are shared by every caller, so a write must fail instead of corrupting them."""
    cache = TableCache()
    for table in (
        preintegrate(spiky(), 8, step=0.5, cache=cache),
        preintegrate(spiky(), 8, lengths=[0.5, 1.0], cache=cache),
    ):
        assert not table.flags.writeable
        with pytest.raises(ValueError):
            table[0, 0] = 1.0
        with pytest.raises(ValueError):
            table *= 2


@pytest.mark.parametrize("kwargs", [dict(step=0.5), dict(lengths=[0.5, 1.0])], ids=["2d", "3d"])
def test_both_arrays_of_cached_lighting_tables_are_read_only(kwargs):
    """Front and back tables are both shared, so both must refuse writes."""
    tables = lighting_tables(spiky(), 8, cache=TableCache(), **kwargs)
    for array in (tables.front, tables.back):
        assert not array.flags.writeable
        with pytest.raises(ValueError):
            array[..., 0] = 0.5


def test_uncached_tables_are_writable():
    """cache=None hands the caller its own table ("read-only when cached" only)."""
    table = preintegrate(spiky(), 8, step=0.5, cache=None)
    table[0, 0] = 0.0
    light = lighting_tables(spiky(), 8, step=0.5, cache=None)
    light.front[0, 0] = 0.0
    light.back[0, 0] = 0.0
    assert not table[0, 0].any() and not light.front[0, 0].any() and not light.back[0, 0].any()


# ---------------------------------------------------------------------------- memory bound
def _array(nbytes: int) -> np.ndarray:
    return np.zeros(nbytes, dtype=np.uint8)


def test_least_recently_used_entry_is_evicted_first():
    """Touching an entry keeps it: eviction order is by last use, not by insertion."""
    cache = TableCache(max_bytes=300)
    for key in "abc":
        cache.get_or_compute(key, lambda: _array(100))
    assert len(cache) == 3 and cache.nbytes == 300
    cache.get_or_compute("a", lambda: pytest.fail("a is cached"))  # touch a: b is now the oldest
    cache.get_or_compute("d", lambda: _array(100))
    assert "b" not in cache and all(k in cache for k in "acd") and cache.nbytes == 300
    cache.get_or_compute("e", lambda: _array(150))  # needs two evictions: c then a
    assert "c" not in cache and "a" not in cache and all(k in cache for k in "de")
    assert cache.nbytes == 250 and len(cache) == 2


def test_lru_eviction_through_preintegrate():
    """With room for three n=8 tables, a fourth evicts the least recently used one."""
    cache = TableCache(max_bytes=3 * N8_BYTES)
    tf = smooth()
    first = {step: preintegrate(tf, 8, step=step, cache=cache) for step in (0.1, 0.2, 0.3)}
    assert preintegrate(tf, 8, step=0.1, cache=cache) is first[0.1]  # touch
    preintegrate(tf, 8, step=0.4, cache=cache)  # evicts step 0.2
    assert cache.nbytes == 3 * N8_BYTES and len(cache) == 3
    misses = cache.misses
    assert preintegrate(tf, 8, step=0.1, cache=cache) is first[0.1]
    assert preintegrate(tf, 8, step=0.3, cache=cache) is first[0.3]
    assert cache.misses == misses
    again = preintegrate(tf, 8, step=0.2, cache=cache)
    assert again is not first[0.2] and cache.misses == misses + 1
    np.testing.assert_array_equal(again, first[0.2])


def test_table_larger_than_the_budget_is_returned_but_not_stored(computations):
    """A table that cannot fit is still the right answer, but must not evict everything else."""
    cache = TableCache(max_bytes=N8_BYTES)
    tf = smooth()
    small = preintegrate(tf, 8, step=0.5, cache=cache)
    big = preintegrate(tf, 9, step=0.5, cache=cache)
    assert big.shape == (9, 9, 4)
    np.testing.assert_array_equal(big, preintegrate(tf, 9, step=0.5, cache=None))
    assert len(cache) == 1 and cache.nbytes == N8_BYTES
    assert preintegrate(tf, 8, step=0.5, cache=cache) is small
    again = preintegrate(tf, 9, step=0.5, cache=cache)
    assert again is not big and cache.misses == 3 and len(computations) == 4
    light = lighting_tables(tf, 8, step=0.5, cache=cache)  # 2 * N8_BYTES: not stored either
    assert isinstance(light, LightingTables) and len(cache) == 1


def test_zero_budget_stores_nothing():
    """max_bytes=0 is a valid way to switch caching off: every request computes."""
    cache = TableCache(max_bytes=0)
    tf = smooth()
    a = preintegrate(tf, 8, step=0.5, cache=cache)
    b = preintegrate(tf, 8, step=0.5, cache=cache)
    assert a is not b and len(cache) == 0 and cache.nbytes == 0 and cache.misses == 2
    np.testing.assert_array_equal(a, b)


@STABLE
@given(
    max_bytes=st.integers(0, 400),
    requests=st.lists(st.tuples(st.integers(0, 6), st.integers(1, 250)), max_size=40),
)
def test_cache_follows_an_lru_model_and_never_exceeds_its_budget(max_bytes, requests):
    """Against a reference LRU model: same hits, same contents, nbytes <= max_bytes after every step."""
    cache = TableCache(max_bytes=max_bytes)
    model: OrderedDict[int, tuple[np.ndarray, int]] = OrderedDict()
    sizes: dict[int, int] = {}
    for key, size in requests:
        size = sizes.setdefault(key, size)  # a key always names the same value
        made: list[np.ndarray] = []

        def compute(size=size, made=made):
            made.append(_array(size))
            return made[-1]

        got = cache.get_or_compute(key, compute)
        if key in model:
            model.move_to_end(key)
            assert got is model[key][0] and not made
        else:
            assert made and got is made[0] and not got.flags.writeable
            if size <= max_bytes:
                model[key] = (got, size)
                while sum(s for _, s in model.values()) > max_bytes:
                    model.popitem(last=False)
        assert cache.nbytes <= max_bytes
        assert cache.nbytes == sum(s for _, s in model.values())
        assert len(cache) == len(model) and all(k in cache for k in model)


def test_clear_empties_the_cache():
    """After clear() nothing is held and the next request computes again."""
    cache = TableCache()
    tf = smooth()
    a = preintegrate(tf, 8, step=0.5, cache=cache)
    lighting_tables(tf, 8, step=0.5, cache=cache)
    assert len(cache) == 2 and cache.nbytes == 3 * N8_BYTES
    cache.clear()
    assert len(cache) == 0 and cache.nbytes == 0
    b = preintegrate(tf, 8, step=0.5, cache=cache)
    assert b is not a and len(cache) == 1
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("max_bytes", [-1, -(1 << 40)])
def test_negative_budget_is_refused(max_bytes):
    """A negative byte budget is a programming error, not a cache that holds nothing."""
    with pytest.raises(ValueError, match="max_bytes"):
        TableCache(max_bytes=max_bytes)


# ------------------------------------------------------------------------------- threading
@pytest.mark.parametrize("function", [preintegrate, lighting_tables])
def test_concurrent_identical_requests_compute_once(function, computations, monkeypatch):
    """Render threads asking for the same table at once must share one computation and one object."""
    counting = tables_module._exact_tables

    def slow(*args, **kwargs):  # widens the race window; nothing here measures time
        time.sleep(0.05)
        return counting(*args, **kwargs)

    monkeypatch.setattr(tables_module, "_exact_tables", slow)
    cache = TableCache()
    tf = spiky()
    threads = 4
    barrier = threading.Barrier(threads)
    results: list[object] = [None] * threads
    errors: list[BaseException] = []

    def worker(k: int) -> None:
        try:
            barrier.wait(timeout=30)
            results[k] = function(tf, 16, step=0.5, cache=cache)
        except BaseException as exc:  # reported below, not lost in the thread
            errors.append(exc)

    pool = [threading.Thread(target=worker, args=(k,)) for k in range(threads)]
    for t in pool:
        t.start()
    for t in pool:
        t.join(timeout=60)
    assert not errors, errors
    assert not any(t.is_alive() for t in pool)
    assert len(computations) == 1
    assert all(r is results[0] for r in results) and results[0] is not None
    assert (cache.misses, cache.hits) == (1, threads - 1)
