"""Tetrahedron orientation and degeneracy: signed volumes, reorientation, dropping flat cells.

Renderers rely on every tetrahedron being positively oriented (its vertices 1, 2, 3 seen
counter-clockwise from vertex 0's opposite side, i.e. a positive signed volume), and on no cell
being flat. Flat cells carry no volume, so dropping them changes no integral.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray


def signed_volumes(points: NDArray, tets: NDArray) -> NDArray[np.float64]:
    """Signed volume of each tetrahedron: det[p1-p0, p2-p0, p3-p0] / 6."""
    p = points[tets]
    a = p[:, 1] - p[:, 0]
    b = p[:, 2] - p[:, 0]
    c = p[:, 3] - p[:, 0]
    return np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0


#: A tetrahedron is flat when it repeats a vertex or |V| <= FLAT_REL_TOL * l**3 (l its longest
#: edge): the one flatness rule, applied on loading (`repair_tets`) and by `tet_mesh.build_mesh`.
FLAT_REL_TOL = 1e-9


def flat_cells(six_volumes: NDArray, longest_edges: NDArray, repeated: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """The flat tetrahedra, from 6 * signed volume, the longest edge and whether a vertex repeats;
    relative to the edge length, so the decision does not depend on units."""
    return repeated | (np.abs(six_volumes) <= 6.0 * FLAT_REL_TOL * longest_edges**3)


@dataclass(frozen=True)
class RepairResult:
    tets: NDArray[np.int64]
    dropped_degenerate: int
    reoriented: int


def repair_tets(points: NDArray, tets: NDArray) -> RepairResult:
    """Drop flat tetrahedra (`flat_cells`) and reorient inverted ones (swap vertices 2 and 3)."""
    tets = np.asarray(tets, dtype=np.int64)
    if len(tets) == 0:
        return RepairResult(tets.reshape(0, 4), 0, 0)
    volumes = signed_volumes(points, tets)
    p = points[tets]
    pairs = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))
    longest = np.max([np.linalg.norm(p[:, a] - p[:, b], axis=1) for a, b in pairs], axis=0)
    repeated = np.zeros(len(tets), dtype=bool)
    for a, b in pairs:
        repeated |= tets[:, a] == tets[:, b]
    flat = flat_cells(6.0 * volumes, longest, repeated)
    inverted = (~flat) & (volumes < 0)
    fixed = tets.copy()
    fixed[inverted, 2], fixed[inverted, 3] = tets[inverted, 3], tets[inverted, 2]
    return RepairResult(np.ascontiguousarray(fixed[~flat]), int(flat.sum()), int(inverted.sum()))
