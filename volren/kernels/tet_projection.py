"""Tetrahedra projected to pixels, and the candidates of each pixel's ray.

Why: a ray through a mesh only needs the cells whose projection covers its pixel. The reference
renderer, the tetrahedral ray caster's near-plane cells and picking all bin cells the same way.

`pixel_coordinates` projects points with the camera's view and projection matrices (pixel centres
at integers, row 0 at the top, DESIGN.md's camera). `projected_boxes` gives each usable
tetrahedron the pixel box holding the centres inside the bounding box of its projection;
tetrahedra wholly before the near or beyond the far plane are culled and one with a vertex behind
the eye gets the whole image. `bin_rows` lists each tetrahedron in the pixels of its box for a
block of rows (CSR arrays: offsets per pixel, tetrahedron ids), so memory follows the block, not
the frame. `ray_far` is the length of each ray from the near plane to the far plane.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


def ray_far(camera, dirs: np.ndarray) -> np.ndarray:
    """Distance along each ray from the near plane (where it starts) to the far plane."""
    near, far = camera.clipping_range
    cos = dirs @ np.asarray(camera.direction, dtype=np.float64)
    return (far - near) / cos


def pixel_coordinates(
    camera, width: int, height: int, points: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(px, py, w): points (n, 3) at pixel coordinates (pixel centres at integers, row 0 at the top)
    and their clip w (<= 0: on or behind the eye's plane, where px, py are the points divided by 1)."""
    matrix = camera.projection_matrix(width / height) @ camera.view_matrix()
    n = len(points)
    px, py, w = np.empty(n), np.empty(n), np.empty(n)
    _pixel_coordinates(
        np.ascontiguousarray(points, dtype=np.float64), matrix, int(width), int(height), px, py, w
    )
    return px, py, w


@njit(nogil=True, cache=True)
def _pixel_coordinates(points, m, width, height, px, py, pw):
    for i in range(points.shape[0]):
        x, y, z = points[i, 0], points[i, 1], points[i, 2]
        w = m[3, 0] * x + m[3, 1] * y + m[3, 2] * z + m[3, 3]
        pw[i] = w
        if not (w > 0.0):
            w = 1.0
        px[i] = ((m[0, 0] * x + m[0, 1] * y + m[0, 2] * z + m[0, 3]) / w + 1.0) * 0.5 * width - 0.5
        py[i] = (1.0 - (m[1, 0] * x + m[1, 1] * y + m[1, 2] * z + m[1, 3]) / w) * 0.5 * height - 0.5


def projected_boxes(
    camera, width: int, height: int, points: np.ndarray, tets: np.ndarray, ok: np.ndarray
) -> np.ndarray:
    """Pixel boxes of the projected tetrahedra whose `ok` is set (see `tet_boxes`)."""
    px, py, w = pixel_coordinates(camera, width, height, points)
    view = camera.view_matrix()
    depth = -(np.asarray(points, dtype=np.float64) @ view[2, :3] + view[2, 3])
    near, far = camera.clipping_range
    return tet_boxes(px, py, w, np.ascontiguousarray(depth), tets, ok, width, height, near, far)


@njit(nogil=True, cache=True)
def tet_boxes(px, py, pw, depth, tets, ok, width, height, near, far):
    """Pixel bounding box (x0, x1, y0, y1) of every tetrahedron's projection; x0 = -1: none.

    px, py: projected vertex positions in pixel-centre units (pixel (i, j) has its centre at
    (i, j), row 0 at the top); pw: clip w (<= 0 behind the eye); depth: eye-space distance along
    the view direction. Pixel centres within 1e-4 pixel of the box count (rounding margin).
    """
    m = tets.shape[0]
    boxes = np.full((m, 4), -1, np.int64)
    eps = 1e-4
    for t in range(m):
        if not ok[t]:
            continue
        dmin = math.inf
        dmax = -math.inf
        behind = False
        xmin = math.inf
        xmax = -math.inf
        ymin = math.inf
        ymax = -math.inf
        for f in range(4):
            v = tets[t, f]
            dmin = min(dmin, depth[v])
            dmax = max(dmax, depth[v])
            if not (pw[v] > 0.0):
                behind = True
            xmin = min(xmin, px[v])
            xmax = max(xmax, px[v])
            ymin = min(ymin, py[v])
            ymax = max(ymax, py[v])
        if dmax < near or dmin > far:
            continue
        if behind:
            x0, x1, y0, y1 = 0, width - 1, 0, height - 1
        else:
            if not (xmax >= -1.0 and xmin <= width and ymax >= -1.0 and ymin <= height):
                continue
            x0 = max(0, int(math.ceil(xmin - eps)))
            x1 = min(width - 1, int(math.floor(xmax + eps)))
            y0 = max(0, int(math.ceil(ymin - eps)))
            y1 = min(height - 1, int(math.floor(ymax + eps)))
            if x1 < x0 or y1 < y0:
                continue
        boxes[t, 0] = x0
        boxes[t, 1] = x1
        boxes[t, 2] = y0
        boxes[t, 3] = y1
    return boxes


@njit(nogil=True, cache=True)
def bin_rows(boxes, width, row0, row1):
    """CSR lists of candidate tetrahedra for the pixels of rows row0 .. row1 - 1 (row-major,
    pixel index relative to the first pixel of row0): (offsets, tetrahedron ids)."""
    n = (row1 - row0) * width
    counts = np.zeros(n + 1, np.int64)
    m = boxes.shape[0]
    for t in range(m):
        if boxes[t, 0] < 0:
            continue
        y0 = max(boxes[t, 2], row0)
        y1 = min(boxes[t, 3], row1 - 1)
        for y in range(y0, y1 + 1):
            base = (y - row0) * width + 1
            for x in range(boxes[t, 0], boxes[t, 1] + 1):
                counts[base + x] += 1
    offsets = np.cumsum(counts)
    fill = offsets[:-1].copy()
    cand = np.empty(offsets[-1], np.int64)
    for t in range(m):
        if boxes[t, 0] < 0:
            continue
        y0 = max(boxes[t, 2], row0)
        y1 = min(boxes[t, 3], row1 - 1)
        for y in range(y0, y1 + 1):
            base = (y - row0) * width
            for x in range(boxes[t, 0], boxes[t, 1] + 1):
                p = base + x
                cand[fill[p]] = t
                fill[p] += 1
    return offsets, cand
