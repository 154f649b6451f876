"""The value histogram behind the 1D TF editor: np.histogram's counts over the finite values,
the integer fast path included, linear and log heights, and one computation per volume."""

from __future__ import annotations

import numpy as np
import pytest

from volren.model.value_histogram import Histogram, compute_histogram, value_histogram
from volren.model.volume import TetVolume, UniformVolume


def test_float_volume_counts_only_finite_values():
    rng = np.random.default_rng(1)
    values = rng.normal(size=(6, 7, 8)).astype(np.float32)
    values[0, 0, :3] = [np.nan, np.inf, -np.inf]
    volume = UniformVolume(values)
    hist = value_histogram(volume, bins=32)
    finite = values[np.isfinite(values)]
    expected, edges = np.histogram(finite, 32, volume.value_range)
    np.testing.assert_array_equal(hist.counts, expected)
    np.testing.assert_allclose(hist.edges, edges)
    assert hist.counts.sum() == values.size - 3


@pytest.mark.parametrize("dtype", [np.int8, np.uint8, np.int16, np.uint16])
@pytest.mark.parametrize("bins", [1, 7, 256])
def test_integer_volumes_match_np_histogram(dtype, bins):
    info = np.iinfo(dtype)
    rng = np.random.default_rng(2)
    lo, hi = max(info.min, -3000), min(info.max, 3000)
    values = rng.integers(lo, hi, size=(9, 10, 11), endpoint=True).astype(dtype)
    volume = UniformVolume(values)
    hist = value_histogram(volume, bins=bins)
    expected, edges = np.histogram(values, bins, volume.value_range)
    np.testing.assert_array_equal(hist.counts, expected)
    np.testing.assert_allclose(hist.edges, edges)


@pytest.mark.parametrize("dtype, chunk", [(np.int16, 100), (np.uint8, 100), (np.uint8, 101), (np.int8, 7)])
def test_integer_path_is_chunked_without_changing_counts(monkeypatch, dtype, chunk):
    """Many chunks, of odd sizes too (bytes are tallied in pairs, the odd one alone)."""
    import volren.model.value_histogram as histograms

    monkeypatch.setattr(histograms, "_TALLY_CHUNK", chunk)
    values = (np.arange(990).reshape(9, 10, 11) * 7919 % 251).astype(dtype)
    value_range = (float(values.min()), float(values.max()))
    hist = compute_histogram(values, 13, value_range)
    np.testing.assert_array_equal(hist.counts, np.histogram(values, 13, value_range)[0])


@pytest.mark.parametrize("dtype", [np.int8, np.uint8, np.int16, np.uint16])
def test_integer_extremes_and_values_outside_the_range(dtype):
    info = np.iinfo(dtype)
    values = np.array([info.min, info.min + 1, -1, 0, 1, 2, 100, info.max - 1, info.max], np.int64)
    values = values[(values >= info.min) & (values <= info.max)].astype(dtype)
    for value_range in ((float(info.min), float(info.max)), (0.0, 100.0), (0.5, 2.5)):
        hist = compute_histogram(values, 3, value_range)
        np.testing.assert_array_equal(hist.counts, np.histogram(values.astype(np.float64), 3, value_range)[0])


def test_tet_volume_uses_point_values():
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], float)
    values = np.array([0.0, 1.0, 1.0, 3.0, np.nan])
    mesh = TetVolume(points, np.array([[0, 1, 2, 3], [1, 2, 3, 4]]), values)
    hist = value_histogram(mesh, bins=3)
    np.testing.assert_array_equal(hist.counts, [1, 2, 1])
    np.testing.assert_allclose(hist.edges, [0.0, 1.0, 2.0, 3.0])


def test_constant_volume_puts_everything_in_one_bin():
    volume = UniformVolume(np.full((2, 3, 4), 5.0))
    hist = value_histogram(volume, bins=8)
    assert hist.counts.sum() == 24
    assert np.count_nonzero(hist.counts) == 1
    assert hist.edges[0] < 5.0 < hist.edges[-1]


def test_linear_and_log_heights():
    hist = Histogram(np.arange(5.0), np.array([0, 1, 9, 99], np.int64))
    np.testing.assert_allclose(hist.heights(), [0.0, 1 / 99, 9 / 99, 1.0])
    np.testing.assert_allclose(hist.heights(log=True), np.log([1, 2, 10, 100]) / np.log(100))
    # log keeps a single value visible next to a large peak; linear makes it a hair
    assert hist.heights(log=True)[1] > 10 * hist.heights()[1]
    empty = Histogram(np.arange(3.0), np.zeros(2, np.int64))
    np.testing.assert_array_equal(empty.heights(log=True), [0.0, 0.0])


def test_one_computation_per_volume_and_bin_count():
    volume = UniformVolume(np.arange(24, dtype=np.float32).reshape(2, 3, 4))
    first = value_histogram(volume)
    assert value_histogram(volume) is first
    assert value_histogram(volume, bins=4) is not first
    twin = UniformVolume(volume.values.copy())
    assert value_histogram(twin) is not first  # keyed on the object, not its contents


def test_bins_must_be_positive():
    with pytest.raises(ValueError, match="at least one bin"):
        value_histogram(UniformVolume(np.zeros((2, 2, 2))), bins=0)
