"""The default TF, derived from the volume histogram: backgrounds transparent, an average ray
through the volume at optical depth 2 (issue 23: CT turned into fog, flow meshes hid the wake)."""

from __future__ import annotations

import numpy as np
import pytest

from volren.model.default_tf import MAX_PEAK, TARGET_DEPTH, default_transfer_function, volume_histogram
from volren.model.value_histogram import compute_histogram, value_histogram
from volren.model.volume import TetVolume, UniformVolume


def mean_depth(volume: UniformVolume, tf) -> float:
    """The oracle, voxel by voxel (not through the histogram): the mean extinction of every value,
    times the voxel lengths across the volume's mean extent."""
    _, alpha = tf.sample(volume.values.reshape(-1).astype(np.float64))
    tau = -np.log1p(-np.minimum(alpha, 1 - 1e-6))
    b = volume.bounds
    return float(tau.mean()) * np.mean([b[1] - b[0], b[3] - b[2], b[5] - b[4]]) / tf.opacity_unit_distance


def ct_like(rng, air_share: float = 0.7, n: int = 40) -> UniformVolume:
    """Air at -1000 HU around soft tissue (0..100) and a little bone (up to 1000)."""
    count = n**3
    values = rng.uniform(0, 100, count)
    values[: int(air_share * count)] = -1000
    values[-count // 100 :] = rng.uniform(300, 1000, count // 100)
    return UniformVolume(rng.permutation(values).reshape(n, n, n).astype(np.int16), spacing=(0.5, 0.5, 0.5))


def test_ct_air_is_transparent_and_an_average_ray_has_depth_two():
    volume = ct_like(np.random.default_rng(1))
    tf = default_transfer_function(volume)
    opacity = lambda v: float(tf.sample([v])[1][0])  # noqa: E731
    assert opacity(-1000) == 0.0 and opacity(-850) == 0.0  # the air peak and its tail
    assert 0 < opacity(50) < opacity(1000) < MAX_PEAK
    assert mean_depth(volume, tf) == pytest.approx(TARGET_DEPTH, rel=0.05)
    assert tf.opacity_unit_distance == 0.5
    lo, hi = tf.color_points[[0, -1], 0]
    assert lo > -1000 and hi == volume.value_range[1]  # viridis over the visible values


def test_a_dominant_top_value_is_transparent_and_what_it_hides_shows():
    """A free stream at the top of the range (oxygen post's outer flow) hid the wake."""
    rng = np.random.default_rng(2)
    values = rng.uniform(0.9, 1.0, 30**3)
    values[: 30**3 // 4] = rng.uniform(0.0, 0.8, 30**3 // 4)
    volume = UniformVolume(rng.permutation(values).reshape(30, 30, 30))
    tf = default_transfer_function(volume)
    assert float(tf.sample([0.95])[1][0]) == 0.0
    assert float(tf.sample([0.7])[1][0]) > 0.0
    assert mean_depth(volume, tf) == pytest.approx(TARGET_DEPTH, rel=0.05)


def test_without_a_background_the_bottom_tenth_is_transparent():
    volume = UniformVolume(np.linspace(0, 10, 20**3).reshape(20, 20, 20))
    tf = default_transfer_function(volume)
    assert float(tf.sample([0.99])[1][0]) == 0.0 and float(tf.sample([1.01])[1][0]) > 0.0
    assert mean_depth(volume, tf) == pytest.approx(TARGET_DEPTH, rel=0.05)


def test_sparse_data_gets_the_strongest_opacity_allowed():
    values = np.zeros((30, 30, 30), np.float32)
    values[15, 15, 10:20] = 1.0  # a thin vessel
    tf = default_transfer_function(UniformVolume(values))
    assert float(tf.sample([1.0])[1][0]) == pytest.approx(MAX_PEAK)


def test_a_meshs_histogram_weighs_points_by_the_volume_of_their_tetrahedra():
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, -3]], float)
    tets = np.array([[0, 1, 2, 3], [0, 2, 1, 4]])  # volumes 1/6 and 3/6
    values = np.array([0.0, 1.0, 1.0, 0.0, 4.0])
    histogram = volume_histogram(TetVolume(points, tets, values))
    bins = len(histogram.counts)
    weights = {0.0: (1 / 6 + 3 / 6) / 4 + 1 / 6 / 4, 1.0: 2 * (1 / 6 + 3 / 6) / 4, 4.0: 3 / 6 / 4}
    for value, weight in weights.items():
        index = min(
            int(np.searchsorted(histogram.edges, value, side="right")) - 1, bins - 1
        )  # np.histogram's bin
        assert histogram.counts[index] == pytest.approx(weight)
    assert histogram.counts.sum() == pytest.approx(4 / 6)


def test_float32_values_at_the_types_limits_are_binned_and_get_a_tf():
    """In float32, 3.4e38 minus -3.4e38 overflows: every value must still find its bin."""
    values = np.full((4, 4, 4), -3.4e38, np.float32)
    values[1:3] = 0.0
    values[3] = 3.4e38
    volume = UniformVolume(values)
    counts = value_histogram(volume).counts
    assert (counts[0], counts[len(counts) // 2], counts[-1], counts.sum()) == (16, 32, 16, 64)
    tf = default_transfer_function(volume)
    assert tf.value_range == volume.value_range == (float(np.float32(-3.4e38)), float(np.float32(3.4e38)))


def test_a_span_beyond_float64s_range_is_binned_exactly():
    values = np.array([-1.7e308, 0.0, 1e308, 1.7e308])
    histogram = compute_histogram(values, 4, (-1.7e308, 1.7e308))
    assert histogram.counts.tolist() == [1, 0, 1, 2]
    assert histogram.edges[[0, 2, 4]].tolist() == [-1.7e308, 0.0, 1.7e308]
    np.testing.assert_allclose(histogram.edges, [-1.7e308, -8.5e307, 0.0, 8.5e307, 1.7e308], rtol=1e-15)
