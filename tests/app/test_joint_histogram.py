"""The value x gradient-magnitude joint histogram against brute-force numpy computations."""

from __future__ import annotations

import gc

import numpy as np
import pytest

from volren.app.core import joint_histogram as jh
from volren.model.tet_mesh import prepare_mesh
from volren.model.volume import TetVolume, UniformVolume

SPACING = (0.5, 1.0, 2.0)  # x, y, z: anisotropic, so a wrong axis order shows


@pytest.fixture(autouse=True)
def fresh_cache():
    jh.clear_cache()
    yield
    jh.clear_cache()


def random_volume(shape=(7, 9, 11), seed=1, nan_at=None) -> UniformVolume:
    values = np.random.default_rng(seed).uniform(-3.0, 5.0, size=shape)
    if nan_at is not None:
        values[nan_at] = np.nan
    return UniformVolume(values, SPACING, (0.0, 0.0, 0.0))


def brute_force(values, spacing, n_values, n_gradients, value_range, gmax):
    """np.gradient (central inside, one-sided at the borders) and np.histogram2d."""
    hx, hy, hz = spacing
    gz, gy, gx = np.gradient(values.astype(np.float64), hz, hy, hx)
    mags = np.sqrt(gx * gx + gy * gy + gz * gz)
    ok = np.isfinite(values) & np.isfinite(mags)
    v, g = values[ok], mags[ok]
    counts, _, _ = np.histogram2d(
        g, v, bins=[n_gradients, n_values], range=[[0.0, gmax], [value_range[0], value_range[1]]]
    )
    return counts, float(np.count_nonzero(g > gmax)), mags


def test_uniform_counts_match_brute_force():
    volume = random_volume(nan_at=(3, 4, 5))
    lo, hi = volume.value_range
    mags = brute_force(volume.values, SPACING, 4, 4, (lo, hi), 1.0)[2]
    gmax = float(np.nanpercentile(mags, 80))  # some samples above the axis
    counts, above, _ = brute_force(volume.values, SPACING, 16, 12, (lo, hi), gmax)
    hist = jh.joint_histogram(volume, n_values=16, n_gradients=12, gradient_max=gmax)
    assert hist.shape == (12, 16)
    assert hist.stride == 1
    np.testing.assert_array_equal(hist.counts, counts)
    assert hist.above == above > 0
    # the NaN voxel and its six neighbours (whose central differences see it) are left out
    assert hist.counts.sum() + hist.above == volume.values.size - 7


def test_value_window_and_orientation():
    """Rows are gradient bins from g = 0 up, columns value bins; values outside the window drop."""
    values = np.zeros((4, 4, 4))
    values[:, :, 2:] = 10.0  # a step along x: |grad| = 10 / (2 h) next to it, 0 far away
    volume = UniformVolume(values, (1.0, 1.0, 1.0))
    hist = jh.joint_histogram(volume, n_values=10, n_gradients=5, gradient_max=10.0, value_range=(-1.0, 9.0))
    # value 0 lies in bin 1 of [-1, 9); value 10 is outside the window and not counted
    assert hist.counts.sum() == 32
    assert hist.counts[0, 1] == 16  # x = 0: gradient 0
    assert hist.counts[2, 1] == 16  # x = 1: central difference 10 / 2 = 5 -> bin 2 of [0, 10)
    assert hist.value_range == (-1.0, 9.0)


def test_log_density():
    volume = random_volume()
    hist = jh.joint_histogram(volume, n_values=8, n_gradients=8, gradient_max=50.0)
    expected = np.log1p(hist.counts) / np.log1p(hist.counts.max())
    np.testing.assert_allclose(hist.log_density, expected)
    assert hist.log_density.max() == 1.0 and hist.log_density.min() == 0.0


def test_large_volumes_are_strided_with_full_resolution_gradients(monkeypatch):
    volume = random_volume(shape=(9, 10, 11), seed=3)
    monkeypatch.setattr(jh, "MAX_SAMPLES", 200)  # 990 points -> stride 2 (5 x 5 x 6 = 150 points)
    hist = jh.joint_histogram(volume, n_values=10, n_gradients=10, gradient_max=40.0)
    assert hist.stride == 2
    hx, hy, hz = SPACING
    gz, gy, gx = np.gradient(volume.values, hz, hy, hx)
    mags = np.sqrt(gx * gx + gy * gy + gz * gz)[::2, ::2, ::2]
    values = volume.values[::2, ::2, ::2]
    counts, _, _ = np.histogram2d(
        mags.ravel(), values.ravel(), bins=[10, 10], range=[[0.0, 40.0], list(volume.value_range)]
    )
    np.testing.assert_array_equal(hist.counts, counts)


def test_gradient_stats_and_default_axis():
    volume = random_volume(shape=(12, 12, 12), seed=5)
    mags = brute_force(volume.values, SPACING, 2, 2, volume.value_range, 1.0)[2]
    stats = jh.gradient_stats(volume)
    assert stats.max == pytest.approx(mags.max())
    assert stats.robust_max == pytest.approx(np.percentile(mags[mags > 0], jh.ROBUST_PERCENTILE))
    hist = jh.joint_histogram(volume)
    assert hist.gradient_max == stats.robust_max == jh.suggested_gradient_max(volume)
    assert hist.shape == (jh.DEFAULT_BINS[1], jh.DEFAULT_BINS[0])


def test_constant_volume_gets_a_usable_axis():
    volume = UniformVolume(np.full((3, 3, 3), 2.0))
    assert jh.suggested_gradient_max(volume) == 1.0
    hist = jh.joint_histogram(volume, n_values=4, n_gradients=4)
    assert hist.value_range == (1.5, 2.5)
    assert hist.counts[0, 2] == 27  # everything at (value 2, gradient 0)


def test_results_are_cached_per_volume_and_released_with_it():
    volume = random_volume()
    first = jh.joint_histogram(volume, gradient_max=10.0)
    assert jh.joint_histogram(volume, gradient_max=10.0) is first
    assert jh.joint_histogram(volume, gradient_max=20.0) is not first
    twin = UniformVolume(volume.values.copy(), SPACING)
    assert jh.joint_histogram(twin, gradient_max=10.0) is not first
    assert len(jh._cache) == 2
    del volume, twin, first
    gc.collect()
    assert len(jh._cache) == 0


# ---------------------------------------------------------------------------- tet meshes
def kuhn_mesh(n: int, field) -> TetVolume:
    """[0, 1]^3 in n^3 cubes, six tets each (Kuhn), values field(points)."""
    axis = np.linspace(0.0, 1.0, n + 1)
    z, y, x = np.meshgrid(axis, axis, axis, indexing="ij")
    points = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)

    def pid(i, j, k):
        return (k * (n + 1) + j) * (n + 1) + i

    paths = [(0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)]
    tets = []
    for k in range(n):
        for j in range(n):
            for i in range(n):
                for path in paths:
                    c = [i, j, k]
                    ids = [pid(*c)]
                    for axis_ in path:
                        c[axis_] += 1
                        ids.append(pid(*c))
                    tets.append(ids)
    return TetVolume(points, np.asarray(tets), field(points))


def test_tet_mesh_uses_per_tet_gradients_centroid_values_and_volume_weights():
    volume = kuhn_mesh(3, lambda p: np.sin(3 * p[:, 0]) + p[:, 1] ** 2 - 2 * p[:, 2])
    p = volume.points[volume.tets]
    v = volume.values[volume.tets]
    edges = p[:, 1:] - p[:, :1]
    grads = np.linalg.solve(edges, (v[:, 1:] - v[:, :1])[..., None])[..., 0]
    mags = np.linalg.norm(grads, axis=1)
    centroid_values = v.mean(axis=1)
    vol = np.abs(np.linalg.det(edges)) / 6.0
    weights = vol / vol.mean()
    lo, hi = volume.value_range
    gmax = float(np.percentile(mags, 90)) * 1.001
    assert np.abs(mags - gmax).min() > 1e-9  # no magnitude on the axis' top edge, where rounding decides
    counts, _, _ = np.histogram2d(
        mags, centroid_values, bins=[6, 9], range=[[0, gmax], [lo, hi]], weights=weights
    )
    hist = jh.joint_histogram(volume, n_values=9, n_gradients=6, gradient_max=gmax)
    np.testing.assert_allclose(hist.counts, counts, atol=1e-12)
    assert hist.above == pytest.approx(weights[mags > gmax].sum())
    assert hist.counts.sum() + hist.above == pytest.approx(len(volume.tets))
    # the renderers' gradients: prepare_mesh's
    np.testing.assert_allclose(np.linalg.norm(prepare_mesh(volume).gradients, axis=1), mags, rtol=1e-9)


def test_tet_mesh_leaves_out_nonfinite_tets():
    volume = kuhn_mesh(2, lambda p: p[:, 0].copy())
    bad = volume.values.copy()
    bad[0] = np.nan  # point (0, 0, 0): in every tet of the first cube
    broken = TetVolume(volume.points, volume.tets, bad)
    hist = jh.joint_histogram(broken, n_values=4, n_gradients=4, gradient_max=2.0)
    touching = np.count_nonzero((broken.tets == 0).any(axis=1))
    assert touching == 6  # the six tets of the first cube share its corner (0, 0, 0)
    # equal volumes, so every other tet counts 1; value x has |grad| = 1: all in gradient bin 2
    assert hist.counts.sum() == pytest.approx(len(broken.tets) - touching)
    assert hist.counts[2].sum() == pytest.approx(hist.counts.sum())


# --------------------------------------------------------------------------------- size
def test_a_256_cubed_volume_is_counted_in_full():
    """2^24 points are within MAX_SAMPLES: every one is counted, none subsampled away. How fast
    that is (the app's target: well under 2 s) is measured by `python -m benchmarks.app_latency`, not asserted."""
    rng = np.random.default_rng(0)
    values = rng.integers(0, 256, size=(256, 256, 256), dtype=np.uint8)
    hist = jh.joint_histogram(UniformVolume(values))
    assert hist.stride == 1
    assert hist.counts.sum() + hist.above == values.size
