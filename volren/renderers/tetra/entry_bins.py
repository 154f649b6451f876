"""Which entry faces each pixel's ray may cross: the boundary faces turned towards the eye,
projected to the image and binned to the pixel centres they cover (with a small margin to spare,
so that a ray through an edge is never missed; the walk's entry test is exact).

A frame projects its entry faces once (`EntryFaces`: each triangle's pixel box and its three edge
lines in pixel units). A ray per pixel bins them by blocks of rows (`bin_triangles`); adaptive
refinement asks for a sparse set of pixels per level, binned through tiles (`bin_tiles`,
`bin_triangles_at`) so that each level costs in proportion to its pixels, not to the faces. Both
give the same lists (same cells, same order). The lists are CSR: offsets per pixel, then cells.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

#: Pixels to spare around a projected face: a ray through its edge is always listed.
MARGIN = 0.01
#: Pixels per side of the tiles that sparse pixel sets are binned through.
TILE = 4


@dataclass(frozen=True)
class EntryFaces:
    """A frame's projected entry faces.

    boxes (k, 5) int64: whole, x0, x1, y0, y1, the pixels whose centres the triangle's bounding
    box (grown by the margin) holds, clipped to the image (x0 > x1 or y0 > y1: none); whole: a
    vertex lies behind the eye, so the triangle is listed in every pixel. edges (k, 3, 3): each
    edge's line (a, b, c) with a x + b y + c the signed distance in pixels of (x, y) from it,
    positive inside (either winding). cells (k,): the cell each face belongs to."""

    boxes: NDArray[np.int64]
    edges: NDArray[np.float64]
    cells: NDArray[np.int64]
    width: int
    height: int
    margin: float


def project_faces(
    px: NDArray,
    py: NDArray,
    behind: NDArray,
    triangles: NDArray,
    cells: NDArray,
    width: int,
    height: int,
    margin: float = MARGIN,
) -> EntryFaces:
    """The entry faces `triangles` (k, 3 vertex ids) with their vertices at pixel coordinates
    (px, py), `behind` where a vertex lies behind the eye."""
    tri = np.ascontiguousarray(triangles, dtype=np.int64).reshape(-1, 3)
    boxes = np.empty((len(tri), 5), np.int64)
    edges = np.empty((len(tri), 3, 3))
    _project(
        np.ascontiguousarray(px, dtype=np.float64),
        np.ascontiguousarray(py, dtype=np.float64),
        np.ascontiguousarray(behind, dtype=np.bool_),
        tri,
        int(width),
        int(height),
        float(margin),
        boxes,
        edges,
    )
    return EntryFaces(
        boxes, edges, np.ascontiguousarray(cells, dtype=np.int64), int(width), int(height), float(margin)
    )


@njit(nogil=True, cache=True)
def _project(px, py, behind, tri, width, height, margin, boxes, edges):
    for i in range(tri.shape[0]):
        a, b, c = tri[i, 0], tri[i, 1], tri[i, 2]
        xs = (px[a], px[b], px[c])
        ys = (py[a], py[b], py[c])
        whole = behind[a] or behind[b] or behind[c]
        lo_x, hi_x = min(xs[0], xs[1], xs[2]) - margin, max(xs[0], xs[1], xs[2]) + margin
        lo_y, hi_y = min(ys[0], ys[1], ys[2]) - margin, max(ys[0], ys[1], ys[2]) + margin
        boxes[i, 0] = whole
        if whole:
            boxes[i, 1], boxes[i, 2], boxes[i, 3], boxes[i, 4] = 0, width - 1, 0, height - 1
        elif not (
            math.isfinite(lo_x) and math.isfinite(hi_x) and math.isfinite(lo_y) and math.isfinite(hi_y)
        ):
            boxes[i, 1], boxes[i, 2], boxes[i, 3], boxes[i, 4] = (
                0,
                -1,
                0,
                -1,
            )  # a non-finite vertex: no pixels
        else:
            boxes[i, 1] = max(0, int(math.ceil(max(lo_x, -1.0))))
            boxes[i, 2] = min(width - 1, int(math.floor(min(hi_x, width))))
            boxes[i, 3] = max(0, int(math.ceil(max(lo_y, -1.0))))
            boxes[i, 4] = min(height - 1, int(math.floor(min(hi_y, height))))
        area = (xs[1] - xs[0]) * (ys[2] - ys[0]) - (ys[1] - ys[0]) * (xs[2] - xs[0])
        sign = 1.0 if area >= 0.0 else -1.0
        for e in range(3):
            ux, uy = xs[e], ys[e]
            ex, ey = xs[(e + 1) % 3] - ux, ys[(e + 1) % 3] - uy
            length = math.sqrt(ex * ex + ey * ey)
            scale = sign / length if length > 0.0 else sign
            line = (-ey * scale, ex * scale, (ey * ux - ex * uy) * scale)
            for k in range(3):
                edges[i, e, k] = line[k] if math.isfinite(line[k]) else 0.0


@njit(nogil=True, cache=True)
def _covers(boxes, edges, i, x, y, margin):
    """Whether pixel centre (x, y) lies in triangle i's box and within `margin` pixels of it."""
    if not (boxes[i, 1] <= x <= boxes[i, 2] and boxes[i, 3] <= y <= boxes[i, 4]):
        return False
    if boxes[i, 0]:
        return True
    for e in range(3):
        if edges[i, e, 0] * x + edges[i, e, 1] * y + edges[i, e, 2] < -margin:
            return False
    return True


@njit(nogil=True, cache=True)
def _bin_rows(boxes, edges, cells, width, row0, row1, margin):
    counts = np.zeros((row1 - row0) * width + 1, np.int64)
    k = boxes.shape[0]
    for phase in range(2):
        if phase == 1:
            offsets = np.cumsum(counts)
            fill = offsets[:-1].copy()
            cand = np.empty(offsets[-1], np.int64)
        for i in range(k):
            for y in range(max(boxes[i, 3], row0), min(boxes[i, 4], row1 - 1) + 1):
                for x in range(boxes[i, 1], boxes[i, 2] + 1):
                    if _covers(boxes, edges, i, x, y, margin):
                        p = (y - row0) * width + x
                        if phase == 0:
                            counts[p + 1] += 1
                        else:
                            cand[fill[p]] = cells[i]
                            fill[p] += 1
    return offsets, cand


def bin_triangles(faces: EntryFaces, row0: int, row1: int) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """The lists of every pixel of rows row0 .. row1 - 1, row-major."""
    return _bin_rows(faces.boxes, faces.edges, faces.cells, faces.width, row0, row1, faces.margin)


@njit(nogil=True, cache=True)
def _bin_tiles(boxes, width, height, tile):
    tiles_x = (width + tile - 1) // tile
    counts = np.zeros(tiles_x * ((height + tile - 1) // tile) + 1, np.int64)
    for phase in range(2):
        if phase == 1:
            offsets = np.cumsum(counts)
            fill = offsets[:-1].copy()
            members = np.empty(offsets[-1], np.int64)
        for i in range(boxes.shape[0]):
            if boxes[i, 1] > boxes[i, 2] or boxes[i, 3] > boxes[i, 4]:
                continue
            for by in range(boxes[i, 3] // tile, boxes[i, 4] // tile + 1):
                for bx in range(boxes[i, 1] // tile, boxes[i, 2] // tile + 1):
                    b = by * tiles_x + bx
                    if phase == 0:
                        counts[b + 1] += 1
                    else:
                        members[fill[b]] = i
                        fill[b] += 1
    return offsets, members


def bin_tiles(faces: EntryFaces, tile: int = TILE) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """CSR lists (offsets per tile, face indices in ascending order) of the faces whose box meets
    each `tile` x `tile` block of pixels (row-major blocks)."""
    return _bin_tiles(faces.boxes, faces.width, faces.height, tile)


@njit(nogil=True, cache=True, parallel=True)
def _bin_pixels(boxes, edges, cells, width, pixels, margin, tile, tile_offsets, tile_members):
    """Two passes over the pixels, each in parallel (a pixel's list depends on nothing else): count
    each pixel's covering faces, then write them at the counts' running sums. Serial, this was a
    quarter of a refined frame of spx (15 of 55 ms at 512x512)."""
    n = pixels.shape[0]
    tiles_x = (width + tile - 1) // tile
    counts = np.zeros(n + 1, np.int64)
    for j in prange(n):
        x, y = pixels[j] % width, pixels[j] // width
        b = (y // tile) * tiles_x + x // tile
        c = 0
        for k in range(tile_offsets[b], tile_offsets[b + 1]):
            if _covers(boxes, edges, tile_members[k], x, y, margin):
                c += 1
        counts[j + 1] = c
    offsets = np.cumsum(counts)
    cand = np.empty(offsets[n], np.int64)
    for j in prange(n):
        x, y = pixels[j] % width, pixels[j] // width
        b = (y // tile) * tiles_x + x // tile
        c = offsets[j]
        for k in range(tile_offsets[b], tile_offsets[b + 1]):
            i = tile_members[k]
            if _covers(boxes, edges, i, x, y, margin):
                cand[c] = cells[i]
                c += 1
    return offsets, cand


def bin_triangles_at(
    faces: EntryFaces, tiles: tuple[NDArray, NDArray], pixels: NDArray[np.int64], tile: int = TILE
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """The lists of some pixels (row-major indices), in their order; `tiles` from `bin_tiles`."""
    return _bin_pixels(faces.boxes, faces.edges, faces.cells, faces.width, pixels, faces.margin, tile, *tiles)


@njit(nogil=True, cache=True)
def gather_lists(offsets, cand, pixels):
    """The CSR lists of some pixels (indices into `offsets`' pixels), in their order."""
    n = pixels.shape[0]
    out_offsets = np.zeros(n + 1, np.int64)
    for i in range(n):
        out_offsets[i + 1] = out_offsets[i] + offsets[pixels[i] + 1] - offsets[pixels[i]]
    out = np.empty(out_offsets[n], np.int64)
    for i in range(n):
        k = out_offsets[i]
        for c in range(offsets[pixels[i]], offsets[pixels[i] + 1]):
            out[k] = cand[c]
            k += 1
    return out_offsets, out


@njit(nogil=True, cache=True)
def merge_lists(o1, c1, o2, c2):
    """Two CSR lists over the same pixels as one."""
    n = o1.shape[0] - 1
    offsets = np.empty(n + 1, np.int64)
    offsets[0] = 0
    for p in range(n):
        offsets[p + 1] = offsets[p] + (o1[p + 1] - o1[p]) + (o2[p + 1] - o2[p])
    cand = np.empty(offsets[n], np.int64)
    for p in range(n):
        k = offsets[p]
        for c in range(o1[p], o1[p + 1]):
            cand[k] = c1[c]
            k += 1
        for c in range(o2[p], o2[p + 1]):
            cand[k] = c2[c]
            k += 1
    return offsets, cand
