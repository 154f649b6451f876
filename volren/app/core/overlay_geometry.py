"""Where the viewport's overlays fall on screen: the outline's edges and the axes triad, no Qt.

Why the camera's own matrices: the outline must line up with the rendered volume to the pixel, so
its corners go through exactly the projection the renderers use (`Camera.view_matrix` and
`projection_matrix` at the frame's aspect), then from normalized device coordinates into the
rectangle the frame is drawn in (x to the right, y down, pixel centres where the frame's are).
Edges that cross the near plane are cut there, as the renderers cut the volume; edges wholly
behind it are left out.

Rectangles are (x, y, width, height) in widget pixels.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from volren.model.camera import Camera, bounds_corners

Rect = tuple[float, float, float, float]

#: The 12 edges of a box as index pairs into `bounds_corners` (corner i + 2 j + 4 k, x fastest).
BOX_EDGES: tuple[tuple[int, int], ...] = (
    (0, 1), (2, 3), (4, 5), (6, 7),  # along x
    (0, 2), (1, 3), (4, 6), (5, 7),  # along y
    (0, 4), (1, 5), (2, 6), (3, 7),  # along z
)  # fmt: skip


def clip_coordinates(camera: Camera, aspect: float, points: ArrayLike) -> NDArray[np.float64]:
    """Homogeneous clip coordinates (n, 4) of world `points` (n, 3), as the renderers project them."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    matrix = camera.projection_matrix(aspect) @ camera.view_matrix()
    return np.concatenate([p, np.ones((len(p), 1))], axis=1) @ matrix.T


def clip_to_pixels(clip: NDArray[np.float64], rect: Rect) -> NDArray[np.float64]:
    """Pixel positions (n, 2) in `rect` of clip coordinates (n, 4) in front of the camera (w > 0)."""
    x, y, width, height = rect
    ndc = clip[:, :2] / clip[:, 3:4]
    return np.stack([x + (ndc[:, 0] + 1.0) * 0.5 * width, y + (1.0 - ndc[:, 1]) * 0.5 * height], axis=1)


def project_points(camera: Camera, aspect: float, rect: Rect, points: ArrayLike) -> NDArray[np.float64]:
    """Pixel positions (n, 2) of world `points` in front of the near plane (others come out NaN)."""
    clip = clip_coordinates(camera, aspect, points)
    pixels = np.full((len(clip), 2), np.nan)
    front = clip[:, 2] + clip[:, 3] >= 0.0
    pixels[front] = clip_to_pixels(clip[front], rect)
    return pixels


def outline_segments(
    camera: Camera, aspect: float, rect: Rect, bounds: Sequence[float]
) -> NDArray[np.float64]:
    """The box `bounds`'s edges on screen, (m, 2, 2): start and end pixel of each visible edge,
    cut at the near plane (m < 12 when some edges lie wholly behind it)."""
    clip = clip_coordinates(camera, aspect, bounds_corners(bounds))
    near = clip[:, 2] + clip[:, 3]  # >= 0 in front of the near plane (OpenGL's z >= -w)
    ends = []
    for i, j in BOX_EDGES:
        a, b, da, db = clip[i], clip[j], near[i], near[j]
        if da < 0.0 and db < 0.0:
            continue
        if da < 0.0:
            a = a + da / (da - db) * (b - a)
        elif db < 0.0:
            b = b + db / (db - da) * (a - b)
        ends.append((a, b))
    if not ends:
        return np.empty((0, 2, 2))
    pixels = clip_to_pixels(np.asarray(ends).reshape(-1, 4), rect)
    return pixels.reshape(-1, 2, 2)


def triad_arms(camera: Camera, length: float) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Screen offsets (3, 2) of the world X, Y and Z axes `length` pixels long as the camera turns
    them (x right, y down; an axis along the view direction shrinks to a point), and the order to
    draw them in: farthest first, so the nearest arm is drawn over the others."""
    view = camera.view_matrix()[:3, :3]  # rows: sideways, up, toward the viewer
    offsets = np.stack([view[0], -view[1]], axis=1) * length  # column a of `view` is world axis a
    order = np.argsort(view[2], kind="stable")  # most negative eye z = farthest from the viewer
    return offsets, order
