"""`python -m benchmarks.resampling_floor`: pixels interpolated half-way between finer rays."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks import resampling_floor


def _sampled(f, n: int) -> np.ndarray:
    """f at the centres of an n x n image on [0, 1]^2, as one channel."""
    c = (np.arange(n) + 0.5) / n
    y, x = np.meshgrid(c, c, indexing="ij")
    return f(x, y)[..., None]


@pytest.mark.parametrize("k", [2, 4, 6])
def test_a_smooth_image_comes_back_at_the_coarse_pixel_centres(k):
    # Catmull-Rom reproduces polynomials up to degree 1 exactly, and is close on a smooth function:
    # the interpolated coarse image is the function at the coarse centres, not a shifted copy.
    def linear(x, y):
        return 0.2 + 0.5 * x + 0.25 * y

    def wave(x, y):
        return 0.5 + 0.25 * np.sin(3 * x) * np.cos(2 * y)

    n = 16
    out = resampling_floor.half_way_downsample(_sampled(linear, k * n), k)
    inner = (slice(1, -1), slice(1, -1))  # the border taps are clamped
    np.testing.assert_allclose(out[inner], _sampled(linear, n)[inner], atol=1e-12)
    out = resampling_floor.half_way_downsample(_sampled(wave, k * n), k)
    assert np.abs(out[inner] - _sampled(wave, n)[inner]).max() < 1e-3


def test_an_edge_between_the_fine_rays_is_what_a_point_sample_cannot_see():
    # a step at x = 0.55, between fine ray 8 (x = 0.53125) and coarse pixel 4's centre (0.5625): the
    # point sample there is 1, the interpolation from the rays on both sides 1/2 (taps 0, 0, 1, 1):
    # the floor the benchmark measures
    k, n = 2, 8

    def step(x, y):
        return (x > 0.55).astype(float)

    out = resampling_floor.half_way_downsample(_sampled(step, k * n), k)
    point = _sampled(step, n)
    assert point[3, 4, 0] == 1.0 and out[3, 4, 0] == pytest.approx(0.5)
    assert np.array_equal(out[:, :4], point[:, :4]) and np.array_equal(out[:, 5:], point[:, 5:])
    assert np.all((out >= 0.0) & (out <= 1.0))


def test_odd_factors_are_a_one_line_error(capsys):
    assert resampling_floor.main(["--factors", "3", "--shared", "/nonexistent"]) == 1
    assert "even" in capsys.readouterr().err
    with pytest.raises(ValueError, match="even"):
        resampling_floor.half_way_downsample(np.zeros((6, 6, 1)), 3)
