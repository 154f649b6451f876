"""Image-space adaptive refinement (Levoy, "Volume rendering by adaptive refinement", 1990): cast
rays on a coarse grid of pixels, and cast more only in the blocks whose corner colours differ.

A ray caster pays per pixel. Where the image is smooth (empty background, soft interiors) the
colours between four rays `stride` pixels apart are well predicted by bilinear interpolation; where
the corners differ by more than `tolerance` (any premultiplied RGBA channel), or some corner rays
see nothing (alpha 0) and others do, the block is split in four and its edge midpoints and centre
are cast, down to single pixels: silhouettes are followed to the pixel however faint, so no
interpolated haze spreads into the background. The error is then bounded
by how much a block's colours can vary between corners that agree, which is small for smooth images
and large only for features thinner than the stride that no corner ray touches: those are missed.
With stride 1 every pixel is cast and the image is exact.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numba import njit
from numpy.typing import NDArray

from volren.kernels.image_stride import STRIDE_RULE, is_stride
from volren.model.progress import ProgressCallback

__all__ = ["STRIDE_RULE", "CastRays", "is_stride", "refine_image"]

#: cast(pixel indices, sorted, row-major) -> (n, 4) premultiplied RGBA of those pixels.
CastRays = Callable[[NDArray[np.int64]], NDArray[np.floating]]


def refine_image(
    cast: CastRays,
    width: int,
    height: int,
    stride: int,
    tolerance: float,
    progress: ProgressCallback | None = None,
) -> tuple[NDArray[np.floating], int]:
    """The (height * width, 4) image (in the dtype `cast` returns) and the number of rays cast.

    The blocks of each level are `stride` pixels wide (the last row and column of blocks are cut at
    the image's edge); a block whose four corners differ by at most `tolerance` and agree on
    whether they see anything is filled by bilinear interpolation between them, the others are
    split until the blocks are one pixel wide.
    Cast pixels are never overwritten by interpolation."""
    image: NDArray[np.floating] | None = None  # the cast rays' dtype, allocated at the first cast
    done = np.zeros(height * width, dtype=bool)
    wanted = np.zeros(height * width, dtype=bool)
    cast_count = 0

    def sample(xs: NDArray[np.int64], ys: NDArray[np.int64], spacing: int, count: int) -> None:
        """Cast the points of a count x count lattice `spacing` apart at each (x, y) not cast yet."""
        nonlocal cast_count, image
        index = _new_pixels(xs, ys, spacing, count, width, height, done, wanted)
        if index.size:
            rgba = cast(index)
            if image is None:
                image = np.zeros((height * width, 4), dtype=rgba.dtype)
            _scatter(image, index, rgba)
            cast_count += int(index.size)

    x0: NDArray[np.int64]
    y0: NDArray[np.int64]
    x0, y0 = np.meshgrid(
        np.arange(0, max(width - 1, 1), stride, dtype=np.int64),
        np.arange(0, max(height - 1, 1), stride, dtype=np.int64),
    )
    x0, y0 = x0.ravel(), y0.ravel()
    size = stride
    sample(x0, y0, size, 2)  # the blocks' corners
    levels = int(math.log2(stride))
    for level in range(levels):
        assert image is not None  # the first level cast at least the image's corner pixel
        xa, ya = np.minimum(x0, width - 1), np.minimum(y0, height - 1)
        xb, yb = np.minimum(x0 + size, width - 1), np.minimum(y0 + size, height - 1)
        split = _split(image, width, xa, ya, xb, yb, tolerance)
        keep = ~split
        _fill(image, done, width, xa[keep], ya[keep], xb[keep], yb[keep])
        half = size // 2
        x0, y0 = x0[split], y0[split]
        # the children's corners: the parents' corners (cast already), edge midpoints and centres
        sample(x0, y0, half, 3)
        x0 = np.concatenate([x0 + dx for dx in (0, half, 0, half)])
        y0 = np.concatenate([y0 + dy for dy in (0, 0, half, half)])
        size = half
        if progress is not None:
            progress((level + 1) / levels)
    if not levels and progress is not None:
        progress(1.0)
    assert image is not None  # the first level casts at least the image's corner pixel
    return image, cast_count


@njit(nogil=True, cache=True)
def _new_pixels(xs, ys, spacing, count, width, height, done, wanted):
    """The pixels of a count x count lattice `spacing` apart at each (x, y) (clamped to the image)
    not cast yet, sorted, each once; marked done. `wanted` is all False on entry and on return (a
    scan of the image is cheaper than a sort, and than listing every lattice point first)."""
    n = 0
    for k in range(xs.shape[0]):
        for j in range(count):
            row = min(ys[k] + j * spacing, height - 1) * width
            for i in range(count):
                p = row + min(xs[k] + i * spacing, width - 1)
                if not done[p] and not wanted[p]:
                    wanted[p] = True
                    n += 1
    index = np.empty(n, np.int64)
    q = 0
    for p in range(wanted.shape[0]):
        if wanted[p]:
            wanted[p] = False
            done[p] = True
            index[q] = p
            q += 1
            if q == n:
                break
    return index


@njit(nogil=True, cache=True)
def _scatter(image, index, rgba):
    """image[index] = rgba."""
    for q in range(index.shape[0]):
        for ch in range(4):
            image[index[q], ch] = rgba[q, ch]


@njit(nogil=True, cache=True)
def _split(image, width, xa, ya, xb, yb, tolerance):
    """Which blocks split: their corners differ by more than `tolerance` in some channel, or some
    corner rays see nothing (alpha 0) and others do (a silhouette is followed down to pixels)."""
    split = np.zeros(xa.shape[0], dtype=np.bool_)
    for k in range(xa.shape[0]):
        a, b = ya[k] * width + xa[k], ya[k] * width + xb[k]
        c, d = yb[k] * width + xa[k], yb[k] * width + xb[k]
        for ch in range(4):
            lo = min(image[a, ch], image[b, ch], image[c, ch], image[d, ch])
            hi = max(image[a, ch], image[b, ch], image[c, ch], image[d, ch])
            if hi - lo > tolerance:
                split[k] = True
        covered = (image[a, 3] > 0.0) + (image[b, 3] > 0.0) + (image[c, 3] > 0.0) + (image[d, 3] > 0.0)
        if 0 < covered < 4:
            split[k] = True
    return split


@njit(nogil=True, cache=True)
def _fill(image, done, width, xa, ya, xb, yb):
    """Bilinear interpolation between each block's four corner pixels into its pixels not cast."""
    for k in range(xa.shape[0]):
        x0, y0, x1, y1 = xa[k], ya[k], xb[k], yb[k]
        a, b = y0 * width + x0, y0 * width + x1
        c, d = y1 * width + x0, y1 * width + x1
        for y in range(y0, y1 + 1):
            wy = (y - y0) / max(y1 - y0, 1)
            for x in range(x0, x1 + 1):
                p = y * width + x
                if done[p]:
                    continue
                wx = (x - x0) / max(x1 - x0, 1)
                for ch in range(4):
                    top = (1.0 - wx) * image[a, ch] + wx * image[b, ch]
                    bottom = (1.0 - wx) * image[c, ch] + wx * image[d, ch]
                    image[p, ch] = (1.0 - wy) * top + wy * bottom
