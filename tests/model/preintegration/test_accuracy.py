"""The exact tables against their definitions: brute force, the continuous integral, and the
closed forms and composition laws the optical model implies."""

from __future__ import annotations

import numpy as np
import pytest

from tests.model.preintegration.tfs import on_nodes, smooth, spiky
from volren.model.preintegration import preintegrate, preintegrate_approximate, preintegrate_brute_force
from volren.model.transfer_function import TransferFunction1D
from volren.renderers.reference import segment_rgba


def composite(front: np.ndarray, back: np.ndarray) -> np.ndarray:
    """Premultiplied front-over-back in float64."""
    front = front.astype(np.float64)
    return front + (1.0 - front[..., 3:4]) * back.astype(np.float64)


@pytest.mark.parametrize(
    "n, oversampling", [(2, 1), (2, 3), (3, 1), (3, 3), (17, 1), (17, 3), (64, 1), (64, 3), (512, 1)]
)
def test_subrange_integration_matches_brute_force(n, oversampling):
    """Lum et al.'s O(n^2) method computes the same table as compositing every entry's bins."""
    tf = spiky()
    fast = preintegrate(tf, n, step=1.5, oversampling=oversampling, cache=None)
    slow = preintegrate_brute_force(tf, n, step=1.5, oversampling=oversampling)
    assert fast.dtype == np.float32 and fast.shape == (n, n, 4)
    assert np.abs(fast.astype(np.float64) - slow).max() <= 1e-6


def test_3d_table_matches_brute_force_and_the_2d_tables():
    """Each layer of a 3D table is the 2D table of that length (same computation per length)."""
    tf = spiky()
    lengths = [0.0, 0.01, 0.7, 3.0, 40.0]
    table = preintegrate(tf, 33, lengths=lengths, cache=None)
    assert table.shape == (5, 33, 33, 4)
    brute = preintegrate_brute_force(tf, 33, lengths=lengths)
    assert np.abs(table.astype(np.float64) - brute).max() <= 1e-6
    assert not table[0].any()  # a zero-length segment is transparent
    for k, length in enumerate(lengths[1:], start=1):
        np.testing.assert_array_equal(table[k], preintegrate(tf, 33, step=length, cache=None))


@pytest.mark.parametrize("step", [0.05, 0.5, 5.0])
def test_error_against_the_continuous_integral_falls_as_n_t_squared(step):
    """At fixed values (nodes of every table size used), the max error against the float64
    adaptive integral falls about 16x per 4x more TF bins, with either more entries or more
    oversampling, until it meets the float32 floor."""
    tf = spiky()
    coarse = 16
    pairs = np.random.default_rng(3).integers(0, coarse, (60, 2))
    pairs[:6, 1] = pairs[:6, 0]
    values = pairs / (coarse - 1)
    truth = segment_rgba(tf, values[:, 0], values[:, 1], step)

    def error(refine: int, oversampling: int) -> float:
        n = (coarse - 1) * refine + 1
        table = preintegrate(tf, n, step=step, oversampling=oversampling, cache=None)
        return float(np.abs(table[pairs[:, 0] * refine, pairs[:, 1] * refine] - truth).max())

    by_n = [error(k, 1) for k in (1, 4, 16)]
    by_nt = [error(1, m) for m in (1, 4, 16)]
    floor = 1e-8
    for errors in (by_n, by_nt):
        for coarser, finer in zip(errors, errors[1:]):
            assert finer <= max(coarser / 8, floor), errors
    # n_t is what matters: 4x the entries and 4x the bins per entry agree
    assert by_nt[1] == pytest.approx(by_n[1], rel=0.05, abs=floor)
    assert by_n[-1] <= 1e-4 * (step / 5.0) + floor


def test_narrow_spike_keeps_its_full_optical_depth_at_any_table_size():
    """A spike far narrower than a bin is neither lost nor smeared: the opacity of a segment
    across it is exact for every n (the bins carry exact means of the extinction)."""
    tf = TransferFunction1D([[0, 1, 1, 1]], [[0, 0], [0.5003, 0], [0.5004, 1], [0.5005, 0], [1, 0]])
    # integral of tau = -ln(max(1 - a, 1e-6)) over the triangle: 2e-4 * mean over a in [0, 1] = 2e-4 (1 - 1e-6)
    depth = 2e-4 * (1 - 1e-6)
    for n in (3, 8, 100, 1000):
        table = preintegrate(tf, n, step=1.0, cache=None)
        # the segment from 0 to 1 spends 1 unit of length per unit of value
        assert table[0, n - 1, 3] == pytest.approx(-np.expm1(-depth), rel=1e-5)
        assert table[n - 1, 0, 3] == pytest.approx(-np.expm1(-depth), rel=1e-5)


def test_diagonal_is_the_homogeneous_closed_form():
    tf = spiky()
    n = 50
    for step in (1e-3, 0.4, 30.0):
        table = preintegrate(tf, n, step=step, cache=None)
        values = np.linspace(0, 1, n)
        rgb, _ = tf.sample(values)
        alpha = -np.expm1(-tf.extinction(values) * step)
        diag = table[np.arange(n), np.arange(n)]
        np.testing.assert_allclose(diag[:, 3], alpha, rtol=1e-6, atol=1e-12)
        np.testing.assert_allclose(diag[:, :3], rgb * alpha[:, None], rtol=1e-6, atol=1e-12)


def test_constant_tf_gives_one_entry_everywhere():
    """Lum's check: with a constant TF every (front, back) pair is the same homogeneous segment."""
    tf = TransferFunction1D.constant(0.3, color=(0.2, 0.5, 0.9), opacity_unit_distance=0.7)
    table = preintegrate(tf, 40, step=2.0, value_range=(-5.0, 11.0), oversampling=2, cache=None)
    alpha = -np.expm1(np.log1p(-0.3) / 0.7 * 2.0)
    expected = np.array([0.2 * alpha, 0.5 * alpha, 0.9 * alpha, alpha])
    np.testing.assert_allclose(table.reshape(-1, 4), np.broadcast_to(expected, (1600, 4)), rtol=2e-6)


def test_splitting_a_segment_and_compositing_the_halves_equals_the_whole():
    """For a TF linear between the table's values, entry (i, j) over length d is entry (i, mid)
    over d / 2 composited over entry (mid, j) over d / 2, in both directions, and both sides agree
    with the continuous integral (2.3e-5 measured with the default n_t of 1041; the bound leaves
    room for the n_t^-2 discretisation error to be 4x larger, not for a wrong composition)."""
    n = 41
    tf = on_nodes(n)
    whole = preintegrate(tf, n, step=3.0, cache=None)
    half = preintegrate(tf, n, step=1.5, cache=None)
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    even = (i - j) % 2 == 0
    i, j = i[even], j[even]
    mid = (i + j) // 2
    joined = composite(half[i, mid], half[mid, j])
    assert np.abs(joined - whole[i, j]).max() <= 1e-6
    pick = np.random.default_rng(0).choice(len(i), 40, replace=False)
    truth = segment_rgba(tf, i[pick] / (n - 1), j[pick] / (n - 1), 3.0)
    assert np.abs(joined[pick] - truth).max() <= 1e-4


@pytest.mark.parametrize("k", [2, 3, 7, 10])
def test_step_invariance_of_a_homogeneous_slab(k):
    """k segments of length d composited equal one segment of length k d (diagonal entries)."""
    tf = smooth()
    n = 64
    d = 0.37
    short = preintegrate(tf, n, step=d, cache=None)
    long = preintegrate(tf, n, step=k * d, cache=None)
    diag = np.arange(n)
    acc = np.zeros((n, 4))
    for _ in range(k):
        acc = composite(acc, short[diag, diag])
    assert np.abs(acc - long[diag, diag]).max() <= 1e-6


def test_tables_are_orientated_front_to_back():
    """Entry [i, j] has s_i at the front: a slab that is opaque and red at low values and green at
    high values looks red from the low side and green from the high side."""
    tf = TransferFunction1D([[0, 1, 0, 0], [1, 0, 1, 0]], [[0, 1], [1, 1]])
    table = preintegrate(tf, 16, step=100.0, cache=None)
    assert table[0, 15, 0] > 0.99 and table[0, 15, 1] < 0.01
    assert table[15, 0, 1] > 0.99 and table[15, 0, 0] < 0.01
    coarse = preintegrate(tf, 16, step=100.0, oversampling=1, cache=None)  # one opaque bin: its mean colour
    np.testing.assert_allclose(coarse[0, 15, :2], [29 / 30, 1 / 30], rtol=1e-5)
    np.testing.assert_allclose(table[0, 15, 3], table[15, 0, 3], rtol=1e-7)  # opacity is symmetric


def test_approximate_table_has_exact_opacity_and_unattenuated_colour():
    """Engel's table: opacity from the integral function (exact), colour = d * mean(q), which for
    a homogeneous segment of optical depth x exceeds the exact colour by x / (1 - exp(-x))."""
    tf = spiky()
    n = 65
    approx = preintegrate_approximate(tf, n, step=0.2)
    exact = preintegrate(tf, n, step=0.2, cache=None)
    np.testing.assert_allclose(approx[..., 3], exact[..., 3], rtol=1e-5, atol=1e-7)
    assert np.all(approx[..., :3] >= exact[..., :3] - 1e-6)  # no self-attenuation: never less colour
    homogeneous = TransferFunction1D.constant(0.4, color=(0.5, 0.5, 0.5))
    for step in (0.1, 1.0, 3.0):
        x = -np.log1p(-0.4) * step
        entry = preintegrate_approximate(homogeneous, 4, step=step)[1, 2]
        alpha = -np.expm1(-x)
        assert entry[3] == pytest.approx(alpha, rel=1e-6)
        assert entry[0] == pytest.approx(min(0.5 * alpha * x / -np.expm1(-x), 1.0), rel=1e-6)
