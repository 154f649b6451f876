"""The packed face planes of tetrahedra in one parallel pass (what the cell walk clips against).

Why not `PreparedMesh.planes` and `pack_planes` in numpy: on oxygen (513k cells) they made six
(m, 4, 3) float64 temporaries and took 1.5 s of every one-shot render, more than the frame; this
kernel computes each face's plane in registers, ~20x faster.

The arithmetic is the same as `model.tet_mesh.face_planes` followed by
`renderers.tetra.traversal.pack_planes`: face f (opposite vertex f) is anchored at its vertex with
the lowest index, its normal is the cross product of the edges to the other two in index order,
so the two cells of a face compute the same normal from the same numbers, and their inward
planes are exact negations (module docstring of `model.tet_mesh`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

#: Face f's vertices (opposite vertex f), as in `model.tet_mesh.FACE_VERTICES`.
_FACES = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]], dtype=np.int64)


@njit(nogil=True, parallel=True, cache=True)
def _packed(points, tets, faces, out):
    for t in prange(tets.shape[0]):
        for f in range(4):
            a = tets[t, faces[f, 0]]
            b = tets[t, faces[f, 1]]
            c = tets[t, faces[f, 2]]
            if a > b:
                a, b = b, a
            if b > c:
                b, c = c, b
            if a > b:
                a, b = b, a
            ux = points[b, 0] - points[a, 0]
            uy = points[b, 1] - points[a, 1]
            uz = points[b, 2] - points[a, 2]
            vx = points[c, 0] - points[a, 0]
            vy = points[c, 1] - points[a, 1]
            vz = points[c, 2] - points[a, 2]
            nx = uy * vz - uz * vy
            ny = uz * vx - ux * vz
            nz = ux * vy - uy * vx
            o = tets[t, f]
            side = (
                nx * (points[o, 0] - points[a, 0])
                + ny * (points[o, 1] - points[a, 1])
                + nz * (points[o, 2] - points[a, 2])
            )
            sigma = 1.0 if side > 0.0 else -1.0
            length = math.sqrt(nx * nx + ny * ny + nz * nz)
            scale = sigma / (length if length > 0.0 else 1.0)
            ix = nx * scale
            iy = ny * scale
            iz = nz * scale
            out[t, f, 0] = ix
            out[t, f, 1] = iy
            out[t, f, 2] = iz
            out[t, f, 3] = -(ix * points[a, 0] + iy * points[a, 1] + iz * points[a, 2])


def packed_face_planes(points: NDArray[np.float64], tets: NDArray[np.int64]) -> NDArray[np.float64]:
    """(m, 4, 4) inward unit plane equations (N, D) of the faces of `tets` (m, 4): N . x + D is
    the signed distance from face f (opposite vertex f); flat faces get zero planes."""
    out = np.empty((len(tets), 4, 4))
    _packed(
        np.ascontiguousarray(points, dtype=np.float64),
        np.ascontiguousarray(tets, dtype=np.int64),
        _FACES,
        out,
    )
    return out
