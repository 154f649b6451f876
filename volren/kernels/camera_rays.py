"""Camera rays for many pixels at once, in one numba pass.

`Camera.rays` defines the rays (the model stays numpy), but its stacked numpy temporaries cost a
large share of a CPU ray-casting frame. Renderers that build rays every frame (and every
refinement level) call `pixel_rays` here: the same unprojection of each pixel centre onto the near
and far planes, several times faster (timings: docs/tetra-benchmark.md, "Camera rays").
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from volren.model.camera import Camera


def pixel_rays(
    camera: Camera, width: int, height: int, x: ArrayLike, y: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """`Camera.rays` (to rounding): origins on the near plane and unit directions (..., 3) of the
    rays through the centres of pixels (x, y) of a width x height image, row 0 at the top."""
    inv = np.linalg.inv(camera.projection_matrix(width / height) @ camera.view_matrix())
    xs, ys = np.broadcast_arrays(np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64))
    origins = np.empty(xs.shape + (3,))
    directions = np.empty(xs.shape + (3,))
    _unproject_pixels(
        np.ascontiguousarray(inv), np.ascontiguousarray(xs).reshape(-1), np.ascontiguousarray(ys).reshape(-1),
        float(width), float(height), origins.reshape(-1, 3), directions.reshape(-1, 3),
    )  # fmt: skip
    return origins, directions


def image_rays(camera: Camera, width: int, height: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """`pixel_rays` for every pixel, (H * W, 3) each in row-major pixel order."""
    pixels = np.arange(width * height)
    return pixel_rays(camera, width, height, pixels % width, pixels // width)


@njit(nogil=True, cache=True)
def _unproject_pixels(inv, xs, ys, width, height, origins, directions):  # pragma: no cover - numba
    """Each pixel centre in normalized device coordinates, through `inv` (the inverse of
    projection @ view) at depth -1 (the origin) and +1 (a point the direction aims at)."""
    sx, sy = 2.0 / width, 2.0 / height
    for i in range(xs.shape[0]):
        cx = (xs[i] + 0.5) * sx - 1.0
        cy = 1.0 - (ys[i] + 0.5) * sy
        w = inv[3, 0] * cx + inv[3, 1] * cy + inv[3, 3]
        near_w = 1.0 / (w - inv[3, 2])
        far_w = 1.0 / (w + inv[3, 2])
        norm = 0.0
        for k in range(3):
            base = inv[k, 0] * cx + inv[k, 1] * cy + inv[k, 3]
            near = (base - inv[k, 2]) * near_w
            d = (base + inv[k, 2]) * far_w - near
            origins[i, k] = near
            directions[i, k] = d
            norm += d * d
        norm = 1.0 / np.sqrt(norm)
        for k in range(3):
            directions[i, k] *= norm
