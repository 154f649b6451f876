"""Exact per-bin means of extinction and emission: the TF side of every table."""

from __future__ import annotations

import numpy as np
import pytest

from volren.model.preintegration.tf_bins import atom_means, tf_bins
from volren.model.transfer_function import MAX_OPACITY, TransferFunction1D


def graded_quadrature(a0, a1, c0, c1):
    """Gauss-Legendre on pieces where 1 - a grows by at most 1.5x (tau = -ln(1 - a) is analytic
    there): an independent float64 evaluation of the two means."""
    w0, w1 = 1 - a0, 1 - a1
    lo, hi = min(w0, w1), max(w0, w1)
    ws = [lo]
    while ws[-1] * 1.5 < hi:
        ws.append(ws[-1] * 1.5)
    ws.append(hi)
    ts = np.array([0.0, 1.0]) if w1 == w0 else np.sort(np.clip([(w - w0) / (w1 - w0) for w in ws], 0, 1))
    ts[0], ts[-1] = 0.0, 1.0
    x, weights = np.polynomial.legendre.leggauss(30)
    m0, m1 = 0.0, np.zeros(3)
    for ta, tb in zip(ts[:-1], ts[1:]):
        t = ta + (tb - ta) * (x + 1) / 2
        wq = weights * (tb - ta) / 2
        tau = -np.log(w0 + (w1 - w0) * t)
        m0 += (wq * tau).sum()
        m1 += (wq[:, None] * (c0 + (c1 - c0) * t[:, None]) * tau[:, None]).sum(0)
    return m0, m1


def test_atom_means_are_exact():
    """Closed forms and series against quadrature, including opacities at the clamp and nearly
    equal ends (where the closed forms would cancel)."""
    rng = np.random.default_rng(0)
    worst = 0.0
    for trial in range(400):
        a0, a1 = rng.uniform(0, MAX_OPACITY, 2)
        if trial % 3 == 0:
            a1 = float(np.clip(a0 + rng.normal() * 1e-4, 0, MAX_OPACITY))
        if trial % 5 == 0:
            a0 = 1 - 1e-6 * rng.uniform(1, 10)
        c0, c1 = rng.uniform(0, 1, (2, 3))
        m0, m1 = atom_means(np.array([a0]), np.array([a1]), c0[None], c1[None])
        q0, q1 = graded_quadrature(a0, a1, c0, c1)
        worst = max(worst, abs(m0[0] - q0) / max(1, q0), np.abs(m1[0] - q1).max() / max(1, q0))
    assert worst <= 1e-13


def test_bin_means_match_dense_sampling():
    tf = TransferFunction1D(
        [[0, 1, 0, 0], [0.4, 0, 1, 0], [1, 0, 0, 1]],
        [[0, 0], [0.25, 0.8], [0.5, 0.1], [0.5, 0.6], [1, 0.3]],
        0.5,
    )
    bins = tf_bins(tf, -0.1, 1.1, 12)
    edges = np.linspace(-0.1, 1.1, 13)
    for k in range(12):
        x = np.linspace(edges[k], edges[k + 1], 200001)
        x = 0.5 * (x[1:] + x[:-1])  # midpoints: the step at 0.5 is a bin edge of the dense grid
        tau = tf.extinction(x)
        rgb, _ = tf.sample(x)
        assert bins.tau[k] == pytest.approx(tau.mean(), rel=1e-8)
        if tau.mean() > 0:
            np.testing.assert_allclose(
                bins.color[k], (rgb * tau[:, None]).mean(0) / tau.mean(), rtol=1e-7, atol=1e-9
            )


def test_narrow_spike_keeps_its_weight_and_colour():
    """A spike 1/1000 of a bin wide with its own colour: the bin carries the spike's full optical
    depth and the spike's colour."""
    tf = TransferFunction1D(
        [[0, 0, 0, 1], [0.5, 1, 0, 0], [1, 0, 0, 1]], [[0, 0], [0.4999, 0], [0.5, 0.9], [0.5001, 0], [1, 0]]
    )
    bins = tf_bins(tf, 0, 1, 4)  # bin 2 holds the spike: [0.5, 0.75] and bin 1 [0.25, 0.5]
    depth = (bins.tau * 0.25).sum()
    assert depth == pytest.approx(2 * 0.0001 * (1 + 0.1 * np.log(0.1) / 0.9), rel=1e-9)
    assert np.all(bins.color[1:3, 0] > 0.999) and bins.tau[0] == 0 and bins.tau[3] == 0


def test_degenerate_ranges_use_the_value_itself():
    """lo == hi, and ranges so narrow that bin edges coincide in float64: finite, the TF at that value."""
    tf = TransferFunction1D([[0, 1, 0, 0], [2, 0, 1, 0]], [[0, 0.2], [2, 0.9]])
    point_tau = tf.extinction([1.0])[0]
    for lo, hi in ((1.0, 1.0), (1.0, 1.0 + 4e-16)):
        bins = tf_bins(tf, lo, hi, 64)
        assert np.all(np.isfinite(bins.tau)) and np.all(np.isfinite(bins.color))
        np.testing.assert_allclose(bins.tau, point_tau, rtol=1e-12)
        np.testing.assert_allclose(bins.color, np.broadcast_to([0.5, 0.5, 0.0], (64, 3)), rtol=1e-12)
