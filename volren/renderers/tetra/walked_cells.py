"""The set of cells the walk enters, and its boundary: where rays enter and leave it.

A walk steps from cell to cell only inside this set; at a face with no cell of the set across it
the ray leaves, and the next entry along the ray (a boundary face turned towards the eye, or a
cell the near plane cuts) starts the next walk. The set is the usable cells (flat and non-finite
ones are holes), or, for compositing with a TF, only the usable cells the TF gives some opacity:
cells of zero opacity add nothing, so a ray that would step through a run of them jumps over it
from the run's first face to the next visible cell (Real-Time Volume Graphics, chapter 8, empty-space skipping,
with the mesh's own faces as the skipping structure).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

#: The three corners of face f of a tetrahedron (the face opposite corner f).
FACE_CORNERS = np.array([[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]])


@dataclass(frozen=True)
class WalkedCells:
    """Cells a walk may enter and the faces where it enters or leaves them."""

    cells: NDArray[np.bool_]  # (m,) the cell belongs to the set
    boundary: NDArray[np.bool_]  # (m, 4) the face has no cell of the set across it
    face_cells: NDArray[np.int64]  # (f,) cell of each boundary face
    face_index: NDArray[np.int64]  # (f,) which of its faces (0-3)
    triangles: NDArray[np.int64]  # (f, 3) its corners (point ids)
    face_planes: NDArray[np.float64]  # (f, 4) its inward plane (the cell's packed plane)


def walked_cells(cells: NDArray[np.bool_], tets: NDArray, neighbors: NDArray, packed: NDArray) -> WalkedCells:
    """`WalkedCells` of the set `cells` in a mesh with face neighbours `neighbors` (-1: none)."""
    across = np.where(neighbors >= 0, cells[np.maximum(neighbors, 0)], False)
    boundary = cells[:, None] & ~across
    cell, face = np.nonzero(boundary)
    triangles = np.take_along_axis(tets[cell], FACE_CORNERS[face], axis=1)
    return WalkedCells(
        cells=np.ascontiguousarray(cells),
        boundary=np.ascontiguousarray(boundary),
        face_cells=np.ascontiguousarray(cell, dtype=np.int64),
        face_index=np.ascontiguousarray(face, dtype=np.int64),
        triangles=np.ascontiguousarray(triangles, dtype=np.int64),
        face_planes=np.ascontiguousarray(packed[cell, face]),
    )
