"""Lighting tables for interpolated pre-integrated lighting (Lum, Wilson and Ma 2004)."""

from __future__ import annotations

import numpy as np
import pytest

from tests.model.preintegration.tfs import smooth, spiky
from volren.model.preintegration import lighting_tables, preintegrate, preintegrate_brute_force
from volren.model.transfer_function import TransferFunction1D
from volren.renderers.reference import segment_rgba


def emission_centre(x: np.ndarray) -> np.ndarray:
    return np.where(x < 1e-3, 0.5 - x / 12, 1 / np.maximum(x, 1e-300) - 1 / np.expm1(np.maximum(x, 1e-300)))


@pytest.mark.parametrize("n, oversampling", [(3, 1), (17, 2), (100, 1)])
def test_weighted_tables_match_brute_force(n, oversampling):
    """The global-ramp difference (G - i C) / (j - i) equals weighting every bin directly."""
    tf = spiky()
    fast = lighting_tables(tf, n, step=2.0, oversampling=oversampling, cache=None)
    slow = preintegrate_brute_force(tf, n, step=2.0, oversampling=oversampling, lighting=True)
    assert np.abs(fast.front.astype(np.float64) - slow.front).max() <= 1e-6
    assert np.abs(fast.back.astype(np.float64) - slow.back).max() <= 1e-6


def test_front_plus_back_is_the_plain_table():
    """Lum et al.: the two weightings sum to one, so the tables sum to the unweighted one."""
    tf = spiky()
    for kwargs in ({"step": 0.3}, {"lengths": [0.1, 1.0, 9.0]}):
        plain = preintegrate(tf, 64, cache=None, **kwargs).astype(np.float64)
        lit = lighting_tables(tf, 64, cache=None, **kwargs)
        np.testing.assert_array_equal(lit.opacity, plain[..., 3])
        np.testing.assert_allclose(lit.diffuse_front + lit.diffuse_back, plain[..., :3], rtol=0, atol=1.2e-7)
        np.testing.assert_allclose(lit.specular_front + lit.specular_back, plain[..., 3], rtol=0, atol=1.2e-7)
        for part in (lit.diffuse_front, lit.diffuse_back, lit.specular_front, lit.specular_back):
            assert np.all(part >= 0)
        assert np.all(lit.diffuse_back <= plain[..., :3]) and np.all(lit.specular_back <= plain[..., 3])


def test_homogeneous_segments_split_at_the_emission_centre():
    """A constant TF: the back-weighted share of every entry is the attenuation-weighted mean
    depth of emission, 1/x - 1/(e^x - 1) for optical depth x (exact, near and on the diagonal)."""
    tf = TransferFunction1D.constant(0.6, color=(0.3, 0.6, 0.9), opacity_unit_distance=0.5)
    for step in (1e-4, 0.2, 3.0, 50.0):
        lit = lighting_tables(tf, 24, step=step, cache=None)
        x = -np.log1p(-0.6) / 0.5 * step
        alpha = -np.expm1(-x)
        share = emission_centre(np.array(x))
        np.testing.assert_allclose(lit.specular_back, share * alpha, rtol=2e-5, atol=1e-12)
        np.testing.assert_allclose(lit.diffuse_back[..., 2], 0.9 * share * alpha, rtol=2e-5, atol=1e-12)


def test_weighted_tables_against_the_continuous_integral():
    """Independent check: the back-weighted colour of entry (i, j) is the plain integral of a TF
    whose colour is multiplied by the ramp w(s) = (s - s_i) / (s_j - s_i), 0 at the front and 1
    at the back (sampled densely into a piecewise-linear TF for the float64 oracle)."""
    tf = smooth()
    n = 33
    step = 2.5
    lit = lighting_tables(tf, n, step=step, cache=None)
    rng = np.random.default_rng(5)
    pairs = [(int(i), int(j)) for i, j in rng.integers(0, n, (12, 2)) if i != j][:8] + [(4, 5), (20, 19)]
    for i, j in pairs:
        si, sj = i / (n - 1), j / (n - 1)
        xs = np.linspace(min(si, sj), max(si, sj), 2001)
        rgb, alpha = tf.sample(xs)
        ramp = (xs - si) / (sj - si)
        ramped = TransferFunction1D(
            np.column_stack([xs, rgb * ramp[:, None]]), np.column_stack([xs, alpha]), tf.opacity_unit_distance
        )
        white = TransferFunction1D(np.column_stack([xs, ramp, ramp, ramp]), np.column_stack([xs, alpha]))
        want_diffuse = segment_rgba(ramped, [si], [sj], step)[0, :3]
        want_specular = segment_rgba(white, [si], [sj], step)[0, 0]
        np.testing.assert_allclose(lit.diffuse_back[i, j], want_diffuse, atol=2e-5)
        assert lit.specular_back[i, j] == pytest.approx(want_specular, abs=2e-5)


def test_no_blow_up_next_to_the_diagonal():
    """Entries one step off the diagonal stay close to the diagonal's closed form (the division
    by j - i is by a whole number of table steps, never by a small value difference)."""
    tf = smooth()
    n = 1024
    lit = lighting_tables(tf, n, step=4.0, cache=None)
    k = np.arange(1, n - 1)
    diag = lit.back[k, k].astype(np.float64)
    for other in (k + 1, k - 1):
        assert np.abs(lit.back[k, other] - diag).max() <= 5e-3
    assert np.all(np.isfinite(lit.front)) and np.all(np.isfinite(lit.back))
