"""Tetrahedron orientation, degeneracy and repetition: signed volumes, reorientation, dropping
flat cells, finding repeated points and repeated cells.

Renderers rely on every tetrahedron being positively oriented (its vertices 1, 2, 3 seen
counter-clockwise from vertex 0's opposite side, i.e. a positive signed volume), and on no cell
being flat. Flat cells carry no volume, so dropping them changes no integral. A cell written
twice would be drawn twice by a renderer that integrates cell by cell, and not at all by one
that walks from cell to cell across faces (VTK's ray caster sees every face of a doubled cell
shared by three cells and stops), so every volume keeps one copy (`repeated_tets`).
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


def flat_cells(
    six_volumes: NDArray, longest_edges: NDArray, repeated: NDArray[np.bool_]
) -> NDArray[np.bool_]:
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


def merged_duplicates(points: NDArray, values: NDArray) -> NDArray[np.int64]:
    """For each point, the first point with the same coordinates and the same value (bit for bit).

    Meshes written cell by cell (or stitched from blocks, like blunt fin) repeat points; faces
    between such copies would not match, so rays would leave the mesh and re-enter at every one.
    Copies with different values are kept apart: the field jumps there, and the walk carries the
    value across matched faces."""
    rows = np.empty((len(points), 4))
    rows[:, :3] = points + 0.0  # -0.0 -> 0.0
    rows[:, 3] = values + 0.0
    _, first, inverse = np.unique(
        rows.view(np.dtype((np.void, 32))).ravel(), return_index=True, return_inverse=True
    )
    return first[inverse.ravel()]


def _mixed(ids: NDArray) -> NDArray[np.uint64]:
    """splitmix64 of each id: well-spread 64-bit codes whose sums rarely collide."""
    x = ids.astype(np.uint64) + np.uint64(0x9E3779B97F4A7C15)
    x = (x ^ (x >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    x = (x ^ (x >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return x ^ (x >> np.uint64(31))


def repeated_tets(points: NDArray, tets: NDArray, values: NDArray) -> NDArray[np.bool_]:
    """Which tetrahedra repeat an earlier one: the same four points in any order, after merging
    repeated points (`merged_duplicates`).

    An order-free hash (the sum of a mixed code per point) finds the candidates in O(m) plus one
    sort of m integers; only cells whose hash repeats are compared exactly, so a hash collision
    never merges two different cells."""
    repeated = np.zeros(len(tets), dtype=bool)
    if len(tets) < 2:
        return repeated
    merged = merged_duplicates(points, values)[tets]
    codes = _mixed(np.arange(len(points)))[merged].sum(axis=1, dtype=np.uint64)
    _, inverse, counts = np.unique(codes, return_inverse=True, return_counts=True)
    candidates = np.flatnonzero(counts[inverse.ravel()] > 1)
    if len(candidates) == 0:
        return repeated
    rows = np.ascontiguousarray(np.sort(merged[candidates], axis=1))
    _, first = np.unique(rows.view(np.dtype((np.void, 32))).ravel(), return_index=True)
    repeated[candidates] = True
    repeated[candidates[first]] = False
    return repeated
