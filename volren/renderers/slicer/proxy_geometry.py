"""Proxy geometry for view-aligned slicing (Real-Time Volume Graphics, section 3.3), on the CPU.

A view-aligned slicer draws the volume as a stack of polygons: the intersections of the data's
bounding box with planes perpendicular to the viewing direction, textured from a 3D texture and
blended in depth order. This module computes those polygons with numpy only, for all planes at
once: the 12 box edges are intersected with every plane (Eq. 3.7), duplicates at corners are
merged, and each plane's points are sorted by angle around their centroid, which gives the same
convex polygon as the face-flag path algorithm of Real-Time Volume Graphics, section 3.5.2.

Planes sit on a lattice anchored in the world, ``view_dir . (x - anchor) = k * spacing`` for
integers k, not on the box's nearest corner: when the camera turns a little the planes turn about
fixed points instead of sliding along the view direction, so the sampled image does not "swim".

Conventions: `view_dir` points from the eye into the scene, so a larger ``view_dir . x`` (the
plane's *depth*) is farther away. Polygons are counter-clockwise as seen from the eye (their
right-hand normal points back to the eye), which is OpenGL's default front face.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from volren.errors import VolrenError

#: More slices than this means the spacing is absurdly small for the box (a mistake, not a wish).
MAX_SLICES = 100_000
#: A plane cuts a box in 3 to 6 points.
MAX_POLYGON_VERTICES = 6

#: Corner i of a box is (x_i, y_i, z_i) with bit 0 -> x, bit 1 -> y, bit 2 -> z (x varying fastest,
#: as `volren.model.camera.bounds_corners`).
_CORNER_BITS = np.array([[(i >> a) & 1 for a in range(3)] for i in range(8)], dtype=np.float64)
#: The 12 edges: corner pairs that differ in one bit.
_EDGES = np.array([(i, i | (1 << a)) for a in range(3) for i in range(8) if not i & (1 << a)], dtype=np.intp)

# Relative tolerances (times the scene's length scale): an edge parameter this far outside [0, 1]
# still counts as a hit (planes through corners), points closer than this are one vertex, and a
# polygon thinner than this is a plane that only touches a corner or an edge.
_LAMBDA_TOL = 1e-12
_MERGE_TOL = 1e-10
_AREA_TOL = 1e-18


@dataclass(frozen=True, eq=False)
class SliceStack:
    """The slice polygons of one box for one view, in drawing order.

    `vertices` is padded to 6 vertices per polygon by repeating the last real vertex, so that a
    fixed 4-triangle fan per polygon (instanced drawing) draws only zero-area triangles for the
    padding; `counts` says how many vertices are real.
    """

    vertices: NDArray[np.float64]  # (P, 6, 3) world positions, CCW seen from the eye
    counts: NDArray[np.intp]  # (P,) real vertices per polygon, 3..6
    depths: NDArray[np.float64]  # (P,) view_dir . x of each polygon's plane
    lattice_indices: NDArray[np.int64]  # (P,) k with depth = view_dir . anchor + k * spacing
    view_dir: NDArray[np.float64]  # (3,) unit
    spacing: float
    anchor: NDArray[np.float64]  # (3,)
    box_min: NDArray[np.float64]  # (3,)
    box_max: NDArray[np.float64]  # (3,)

    def __len__(self) -> int:
        return int(self.counts.shape[0])

    def polygons(self) -> list[NDArray[np.float64]]:
        """The polygons as a list of (n, 3) arrays without padding (for inspection and tests)."""
        return [v[:n] for v, n in zip(self.vertices, self.counts, strict=True)]


@dataclass(frozen=True, eq=False)
class SliceMesh:
    """Triangle list (each polygon as a fan) ready for a vertex buffer, in drawing order."""

    positions: NDArray[np.float32]  # (3T, 3) world positions
    texcoords: NDArray[np.float32]  # (3T, 3) in [0, 1]^3: box_min -> 0, box_max -> 1
    slice_indices: NDArray[np.int32]  # (3T,) index of the polygon in the SliceStack


def _vector(value: ArrayLike, what: str) -> NDArray[np.float64]:
    arr = np.asarray(value, dtype=np.float64)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise VolrenError(f"slicing: {what} must be three finite numbers, got {value!r}")
    return arr


def _unit(value: ArrayLike, what: str) -> NDArray[np.float64]:
    v = _vector(value, what)
    norm = float(np.linalg.norm(v))
    if not (norm > 0.0 and np.isfinite(norm)):
        raise VolrenError(f"slicing: {what} must be a non-zero finite vector, got {value!r}")
    return v / norm


def _plane_basis(normal: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(u, w) orthonormal in the plane with u x w = -normal, so increasing atan2(w, u) is CCW seen
    from an eye looking along `normal`."""
    helper = np.zeros(3)
    helper[int(np.argmin(np.abs(normal)))] = 1.0
    u = np.cross(helper, normal)
    u /= np.linalg.norm(u)
    w = np.cross(normal, u)  # u x (n x u) = n, so u x w = n: flip w to get -n
    return u, -w


def slice_polygons(
    box_min: ArrayLike,
    box_max: ArrayLike,
    view_dir: ArrayLike,
    spacing: float,
    anchor: ArrayLike | None = None,
    back_to_front: bool = True,
) -> SliceStack:
    """Intersect the box [box_min, box_max] (world coordinates) with the planes
    ``view_dir . (x - anchor) = k * spacing`` (k integer; anchor defaults to the world origin).

    `view_dir` points from the eye into the scene and is normalised here. Polygons come farthest
    first (`back_to_front`, for "over" blending of back-to-front slices) or nearest first. Planes
    that only touch a corner or an edge of the box give no polygon.
    """
    lo = _vector(box_min, "box_min")
    hi = _vector(box_max, "box_max")
    if not np.all(hi > lo):
        raise VolrenError(f"slicing: the box must have box_max > box_min on every axis, got {lo} and {hi}")
    n = _unit(view_dir, "view_dir")
    step = float(spacing)
    if not (step > 0.0 and np.isfinite(step)):
        raise VolrenError(f"slicing: the slice spacing must be a positive finite number, got {spacing!r}")
    origin = np.zeros(3) if anchor is None else _vector(anchor, "anchor")

    corners = lo + _CORNER_BITS * (hi - lo)  # (8, 3)
    corner_depths = corners @ n
    base = float(origin @ n)
    rel = corner_depths - base
    extent = float(rel.max() - rel.min())
    if extent / step > MAX_SLICES:
        raise VolrenError(
            f"slicing: spacing {step:g} gives about {extent / step:.3g} slices across the box "
            f"(at most {MAX_SLICES}); use a larger spacing"
        )
    k = np.arange(np.ceil(rel.min() / step), np.floor(rel.max() / step) + 1).astype(np.int64)
    if back_to_front:
        k = k[::-1]  # larger depth is farther from the eye
    depths = base + k * step  # (P,)

    # Eq. 3.7 for every (plane, edge): lambda = (d - n.v_i) / (n.e).
    start = corners[_EDGES[:, 0]]  # (12, 3)
    edge = corners[_EDGES[:, 1]] - start
    denom = edge @ n  # (12,)
    scale = float(max(np.abs(lo).max(), np.abs(hi).max(), np.linalg.norm(hi - lo)))
    crosses = np.abs(denom) > 1e-14 * np.linalg.norm(edge, axis=1)
    safe = np.where(crosses, denom, 1.0)
    lam = (depths[:, None] - (start @ n)[None, :]) / safe[None, :]  # (P, 12)
    valid = crosses[None, :] & (lam >= -_LAMBDA_TOL) & (lam <= 1.0 + _LAMBDA_TOL)
    lam = np.clip(lam, 0.0, 1.0)

    # Merge duplicates: distinct edges meet only at corners, and a plane through a corner hits all
    # three of its edges there. Snap hits within tolerance of a corner onto it and keep the first.
    length = np.linalg.norm(edge, axis=1)  # (12,)
    at_start = valid & (lam * length <= _MERGE_TOL * scale)
    at_end = valid & ~at_start & ((1.0 - lam) * length <= _MERGE_TOL * scale)
    lam = np.where(at_start, 0.0, np.where(at_end, 1.0, lam))
    corner_id = np.where(at_start, _EDGES[:, 0], np.where(at_end, _EDGES[:, 1], -1))  # (P, 12)
    one_hot = corner_id[:, :, None] == np.arange(8)  # (P, 12, 8)
    first = (np.cumsum(one_hot, axis=1) == 1) & one_hot
    valid &= (corner_id < 0) | first.any(axis=2)
    points = start[None, :, :] + lam[:, :, None] * edge[None, :, :]  # (P, 12, 3)

    # Sort each plane's points by angle around their centroid, CCW seen from the eye.
    counts = valid.sum(axis=1)
    weight = valid[:, :, None].astype(np.float64)
    centroid = (points * weight).sum(axis=1) / np.maximum(counts, 1)[:, None]
    u, w = _plane_basis(n)
    offset = points - centroid[:, None, :]
    angle = np.arctan2(offset @ w, offset @ u)
    angle = np.where(valid, angle, np.inf)
    order = np.argsort(angle, axis=1, kind="stable")[:, :MAX_POLYGON_VERTICES]
    sorted_points = np.take_along_axis(points, order[:, :, None], axis=1)  # (P, 6, 3)
    counts = np.minimum(counts, MAX_POLYGON_VERTICES)
    slot = np.arange(MAX_POLYGON_VERTICES)
    last = np.maximum(counts - 1, 0)
    pad_from = np.where(slot[None, :] < counts[:, None], slot[None, :], last[:, None])
    vertices = np.take_along_axis(sorted_points, pad_from[:, :, None], axis=1)

    # Drop planes that merely touch a corner or an edge (fewer than 3 points or no area).
    fan = np.cross(vertices[:, 1:-1] - vertices[:, :1], vertices[:, 2:] - vertices[:, :1]).sum(axis=1)
    area = -0.5 * (fan @ n)
    keep = (counts >= 3) & (area > _AREA_TOL * scale * scale)
    return SliceStack(
        vertices=vertices[keep],
        counts=counts[keep].astype(np.intp),
        depths=depths[keep],
        lattice_indices=k[keep],
        view_dir=n,
        spacing=step,
        anchor=origin,
        box_min=lo,
        box_max=hi,
    )


def triangle_fan(stack: SliceStack) -> SliceMesh:
    """Each polygon as the fan (v0, v_j, v_j+1), j = 1..n-2, flattened into a float32 triangle list
    in the stack's drawing order, with 3D texture coordinates of the box (box_min -> 0, box_max -> 1).

    Only real triangles are emitted (n - 2 per polygon), so the mesh covers each polygon exactly once
    and keeps the polygon's CCW winding.
    """
    p = len(stack)
    j = np.arange(1, MAX_POLYGON_VERTICES - 1)  # fan triangles (0, j, j+1), j = 1..4
    real = j[None, :] <= stack.counts[:, None] - 2  # (P, 4)
    corner_ids = np.stack([np.zeros_like(j), j, j + 1], axis=1)  # (4, 3)
    triangles = stack.vertices[:, corner_ids, :]  # (P, 4, 3, 3)
    positions = triangles[real].reshape(-1, 3)
    slice_ids = np.broadcast_to(np.arange(p)[:, None], (p, j.size))[real]
    tex = np.clip((positions - stack.box_min) / (stack.box_max - stack.box_min), 0.0, 1.0)
    return SliceMesh(
        positions=positions.astype(np.float32),
        texcoords=tex.astype(np.float32),
        slice_indices=np.repeat(slice_ids, 3).astype(np.int32),
    )


def sample_distance_along_ray(
    spacing: float, view_dir: ArrayLike, ray_dir: ArrayLike
) -> float | NDArray[np.float64]:
    """The distance between consecutive slice planes measured along a viewing ray:
    spacing / (view_dir . ray_dir) with both directions normalised (book Listing 4.6).

    Under perspective the rays fan out while the planes stay parallel, so off-axis rays cross the
    slabs obliquely and travel spacing / cos(theta) per slice; the fragment shader uses this length
    in the opacity correction, alpha' = 1 - (1 - alpha)^(distance / opacity_unit_distance). Under a
    parallel projection every ray is the view direction and the distance is `spacing`. `ray_dir` may
    be (..., 3); the result is a float or an array of shape (...).
    """
    step = float(spacing)
    if not (step > 0.0 and np.isfinite(step)):
        raise VolrenError(f"slicing: the slice spacing must be a positive finite number, got {spacing!r}")
    n = _unit(view_dir, "view_dir")
    rays = np.asarray(ray_dir, dtype=np.float64)
    if rays.shape[-1:] != (3,) or not np.all(np.isfinite(rays)):
        raise VolrenError(f"slicing: ray directions must be finite 3-vectors, got shape {rays.shape}")
    norms = np.linalg.norm(rays, axis=-1)
    cosine = (rays @ n) / np.where(norms > 0, norms, 1.0)
    if np.any(norms == 0) or np.any(cosine <= 0):
        raise VolrenError("slicing: every ray must point into the scene (positive dot product with view_dir)")
    result = step / cosine
    return float(result) if result.ndim == 0 else result
