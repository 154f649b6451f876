"""Adaptive image refinement against images known exactly: what is cast is exact, what is
interpolated is exact where the image is bilinear over a block, and nothing is cast twice."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from volren.errors import VolrenError
from volren.kernels.image_refinement import STRIDE_RULE, is_stride, refine_image
from volren.renderers.base import OptionSpec


class Caster:
    """Casts from a known (H * W, 4) image, recording every pixel asked for."""

    def __init__(self, truth: np.ndarray):
        self.truth = truth
        self.asked: list[np.ndarray] = []

    def __call__(self, pixels: np.ndarray) -> np.ndarray:
        assert pixels.dtype == np.int64 and np.all(np.diff(pixels) > 0)  # sorted, no repeats
        self.asked.append(pixels.copy())
        return self.truth[pixels]

    @property
    def cast(self) -> np.ndarray:
        return np.concatenate(self.asked) if self.asked else np.zeros(0, np.int64)


def disc(width: int, height: int, radius: float) -> np.ndarray:
    """A disc with a linear ramp inside and a jump of at least 0.4 in alpha at its edge."""
    y, x = np.mgrid[0:height, 0:width].astype(np.float64)
    inside = np.hypot(x - 0.45 * width, y - 0.55 * height) < radius
    alpha = np.where(inside, 0.4 + 0.5 * x / width, 0.0)
    return np.stack([0.3 * alpha, 0.2 * alpha, 0.1 * alpha, alpha], axis=-1).reshape(-1, 4)


def bilinear(width: int, height: int) -> np.ndarray:
    y, x = np.mgrid[0:height, 0:width].astype(np.float64)
    channels = [0.1 + 1e-3 * x, 0.2 + 2e-3 * y, 1e-5 * x * y, 0.5 + 1e-3 * (x - y)]
    return np.stack(channels, axis=-1).reshape(-1, 4)


def test_stride_one_casts_every_pixel_once():
    truth = disc(37, 23, 9.0)
    cast = Caster(truth)
    image, count = refine_image(cast, 37, 23, 1, 0.5)
    assert count == 37 * 23 and np.array_equal(np.sort(cast.cast), np.arange(37 * 23))
    assert np.array_equal(image, truth)


@pytest.mark.parametrize("width, height, stride", [(64, 64, 8), (70, 45, 16), (1, 9, 4), (9, 1, 64)])
def test_a_bilinear_image_is_rebuilt_from_the_coarse_grid_alone(width, height, stride):
    """Bilinear interpolation is exact on a bilinear image, so no block needs splitting, whatever
    the tolerance, and only the corners of the first level's blocks are cast."""
    truth = bilinear(width, height)
    cast = Caster(truth)
    image, count = refine_image(cast, width, height, stride, 1.0)
    nodes_x = np.unique(np.minimum(np.arange(0, max(width - 1, 1) + stride, stride), width - 1))
    nodes_y = np.unique(np.minimum(np.arange(0, max(height - 1, 1) + stride, stride), height - 1))
    assert count == len(nodes_x) * len(nodes_y) == len(cast.cast)
    assert np.abs(image - truth).max() < 1e-12


def test_edges_are_refined_down_to_pixels():
    """A disc with a sharp edge: blocks across the edge are split down to single pixels, so the
    image is exact here, with a fraction of the rays (measured 8.6 %)."""
    truth = disc(128, 96, 30.0)
    cast = Caster(truth)
    image, count = refine_image(cast, 128, 96, 8, 0.05)
    assert np.abs(image - truth).max() < 1e-12
    assert count < 0.15 * 128 * 96


def test_faint_silhouettes_are_followed_to_the_pixel():
    """A faint disc (alpha 0.02, under the tolerance) on an empty background: blocks whose corners
    disagree on seeing anything are split whatever the tolerance, so no interpolated haze spreads
    into the background, and the disc's edge is exact."""
    y, x = np.mgrid[0:96, 0:128].astype(np.float64)
    inside = (np.hypot(x - 60.0, y - 50.0) < 33.0).ravel()
    truth = np.where(inside[:, None], [[0.01, 0.005, 0.0, 0.02]], 0.0)
    image, count = refine_image(Caster(truth), 128, 96, 16, 0.1)
    assert np.all(image[~inside] == 0.0)
    assert np.abs(image - truth).max() < 1e-12
    assert count < 0.2 * 128 * 96


@settings(max_examples=40, deadline=None)
@given(
    width=st.integers(1, 40),
    height=st.integers(1, 40),
    stride_log=st.integers(0, 6),
    tolerance=st.floats(0.0, 1.0),
    seed=st.integers(0, 2**16),
)
def test_cast_pixels_are_exact_and_interpolated_ones_lie_between_the_corners(
    width, height, stride_log, tolerance, seed
):
    """On any image: each pixel is cast at most once, cast pixels keep their value, and every
    other pixel lies within the range of the image (convex combination of cast pixels)."""
    rng = np.random.default_rng(seed)
    truth = rng.random((height * width, 4)) * (rng.random((height * width, 1)) < 0.3)
    cast = Caster(truth)
    image, count = refine_image(cast, width, height, 2**stride_log, tolerance)
    pixels = cast.cast
    assert count == len(pixels) == len(np.unique(pixels)) <= width * height
    assert np.array_equal(image[pixels], truth[pixels])
    assert np.all(image >= truth[pixels].min(axis=0) - 1e-12) and np.all(
        image <= truth[pixels].max(axis=0) + 1e-12
    )


def test_the_image_keeps_the_cast_rays_dtype():
    """A float32 ray caster gets a float32 image (half the memory traffic of float64), its cast
    pixels bit for bit, and float64 stays float64."""
    truth = disc(64, 48, 20.0)
    for dtype in (np.float32, np.float64):
        exact = truth.astype(dtype)
        cast = Caster(exact)
        image, _ = refine_image(cast, 64, 48, 8, 0.02)
        assert image.dtype == dtype
        assert np.array_equal(image[cast.cast], exact[cast.cast])


def test_zero_tolerance_splits_every_block_that_is_not_constant():
    """Tolerance 0 interpolates only between equal corners: on an image with no two equal
    neighbours every pixel is cast."""
    truth = bilinear(33, 17)
    image, count = refine_image(Caster(truth), 33, 17, 8, 0.0)
    assert count == 33 * 17 and np.array_equal(image, truth)


def test_features_thinner_than_the_stride_are_missed():
    """The method's known limit: a one-pixel line that no ray of the coarse grid touches leaves
    every block's corners equal, so it is not seen at stride 8; at stride 1 it is."""
    truth = np.zeros((64 * 64, 4))
    truth.reshape(64, 64, 4)[:, 13, :] = 0.9  # column 13 lies between grid columns 8 and 16
    coarse, _ = refine_image(Caster(truth), 64, 64, 8, 0.01)
    full, _ = refine_image(Caster(truth), 64, 64, 1, 0.01)
    assert coarse.max() == 0.0 and np.array_equal(full, truth)


def test_progress_reports_each_level():
    seen: list[float] = []
    refine_image(Caster(disc(40, 40, 10.0)), 40, 40, 8, 0.05, seen.append)
    assert seen == pytest.approx([1 / 3, 2 / 3, 1.0])
    seen.clear()
    refine_image(Caster(disc(40, 40, 10.0)), 40, 40, 1, 0.05, seen.append)
    assert seen == [1.0]


@pytest.mark.parametrize("stride", [0, 3, 128, 2.0, True, "4", 2**64])
def test_bad_strides(stride):
    spec = OptionSpec("image_stride", 1, "int", "rays every so many pixels", rule=STRIDE_RULE)
    with pytest.raises(VolrenError, match="option image_stride must be 1, 2, 4, 8, 16, 32 or 64"):
        spec.parse(stride, "demo")


@pytest.mark.parametrize("stride", [1, 2, 4, 8, 16, 32, 64])
def test_strides_are_powers_of_two_up_to_64(stride):
    assert is_stride(stride)
