"""3D tables along the length axis: how renderers interpolate in length, and Schulze et al. 2003's
opacity and colour correction of a 2D table used at another length."""

from __future__ import annotations

import numpy as np
import pytest

from tests.model.preintegration.tfs import smooth, spiky
from volren.model.preintegration import LengthAxis, correct_for_length, interpolate_in_length, preintegrate


def all_entries(n: int) -> tuple[np.ndarray, np.ndarray]:
    return np.meshgrid(np.arange(n), np.arange(n), indexing="ij")


def test_axis_is_evenly_spaced_and_positions_invert_it():
    axis = LengthAxis(max_length=6.0, count=12)
    np.testing.assert_allclose(axis.lengths, np.arange(1, 13) * 0.5)
    np.testing.assert_allclose(axis.position(axis.lengths), np.arange(12))
    assert axis.position(0.0) == 0 and axis.position(100.0) == 11


def test_interpolation_reproduces_the_layers():
    tf = spiky()
    axis = LengthAxis(max_length=3.0, count=8)
    table = preintegrate(tf, 40, lengths=axis.lengths, cache=None)
    i, j = all_entries(40)
    for k, length in enumerate(axis.lengths):
        got = interpolate_in_length(table, axis, i, j, length)
        np.testing.assert_allclose(got, table[k], rtol=1e-5, atol=1e-7)


@pytest.mark.parametrize("make_tf", [spiky, smooth])
def test_interpolation_error_falls_as_one_over_count_squared(make_tf):
    """Between layers: opacity exact (optical depth is linear in length), colour per unit opacity
    linear. Max error over lengths between and below the layers and all entries; measured at
    K = 64: 4.5e-5 (spiky), 1.9e-5 (smooth)."""
    tf = make_tf()
    n, max_length = 48, 8.0
    lengths = np.random.default_rng(0).uniform(0, max_length, 12)
    exact = {length: preintegrate(tf, n, step=length, cache=None).astype(np.float64) for length in lengths}
    i, j = all_entries(n)
    errors = []
    for count in (16, 64):
        axis = LengthAxis(max_length, count)
        table = preintegrate(tf, n, lengths=axis.lengths, cache=None)
        got = [interpolate_in_length(table, axis, i, j, length) for length in lengths]
        errors.append(max(np.abs(g - exact[length]).max() for g, length in zip(got, lengths)))
        for g, length in zip(got, lengths):  # the opacity is exact up to float32 rounding
            np.testing.assert_allclose(g[..., 3], exact[length][..., 3], rtol=2e-6, atol=1e-7)
    assert errors[1] <= errors[0] / 8
    assert errors[1] <= 1e-4


def test_segments_longer_than_the_axis_keep_exact_opacity():
    tf = spiky()
    axis = LengthAxis(2.0, 16)
    table = preintegrate(tf, 32, lengths=axis.lengths, cache=None)
    i, j = all_entries(32)
    got = interpolate_in_length(table, axis, i, j, 5.0)
    want = preintegrate(tf, 32, step=5.0, cache=None)
    np.testing.assert_allclose(got[..., 3], want[..., 3], rtol=2e-6, atol=1e-7)
    assert np.all(got[..., :3] <= got[..., 3:] + 1e-7)


def test_correction_scales_opacity_exactly_and_colour_exactly_on_the_diagonal():
    """Schulze et al. 2003: alpha' = 1 - (1 - alpha)^(d'/d) is exact for every entry; C alpha'/alpha is exact
    for homogeneous segments (the diagonal) and approximate elsewhere."""
    tf = spiky()
    n = 64
    base = preintegrate(tf, n, step=1.0, cache=None)
    for ratio in (0.25, 1.0, 3.0):
        corrected = correct_for_length(base, ratio)
        want = preintegrate(tf, n, step=ratio, cache=None).astype(np.float64)
        np.testing.assert_allclose(corrected[..., 3], want[..., 3], rtol=5e-6, atol=1e-7)
        d = np.arange(n)
        np.testing.assert_allclose(corrected[d, d], want[d, d], rtol=5e-6, atol=1e-7)
        assert np.all(corrected[..., :3] <= corrected[..., 3:] + 1e-7)
    np.testing.assert_array_equal(correct_for_length(np.zeros(4), 2.0), np.zeros(4))
    thin = correct_for_length(np.array([0.25, 0.5, 0.0, 0.0]), 2.0)  # emission without absorption
    np.testing.assert_allclose(thin, [0.5, 1.0, 0.0, 0.0])


def test_a_zero_length_is_transparent_even_behind_an_opaque_entry():
    """0 * ln(1 - 1) must not become NaN (found by `volren bench stress`)."""
    out = correct_for_length(np.array([[0.5, 0.5, 0.5, 1.0], [0.2, 0.1, 0.0, 0.3]]), 0.0)
    np.testing.assert_array_equal(np.abs(out), 0.0)
    axis = LengthAxis(1.0, 4)
    table = np.zeros((4, 2, 2, 4), np.float32)
    table[..., 3] = 1.0
    table[..., 0] = 1.0
    assert np.all(np.abs(interpolate_in_length(table, axis, [0, 1], [1, 0], [0.0, 0.0])) == 0.0)
    np.testing.assert_allclose(interpolate_in_length(table, axis, [0], [1], [0.5])[0], [1.0, 0.0, 0.0, 1.0])
