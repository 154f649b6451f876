"""View-aligned slice polygons against exact geometry: planes, box faces, winding, areas, volume."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st

from volren.errors import VolrenError
from volren.renderers.slicer.proxy_geometry import (
    MAX_SLICES,
    SliceStack,
    sample_distance_along_ray,
    slice_polygons,
    triangle_fan,
)

SQRT3 = math.sqrt(3.0)


# ---------------------------------------------------------------------------- independent oracles
def eye_basis(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(right, up) of an eye looking along n: right x up points back to the eye (-n)."""
    helper = np.array([0.0, 1.0, 0.0]) if abs(n[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    right = np.cross(n, helper)
    right /= np.linalg.norm(right)
    up = np.cross(right, n)
    return right, up


def to_2d(poly: np.ndarray, n: np.ndarray) -> np.ndarray:
    right, up = eye_basis(n)
    return np.stack([poly @ right, poly @ up], axis=1)


def shoelace(pts: np.ndarray) -> float:
    """Signed area, positive for counter-clockwise."""
    x, y = pts[:, 0], pts[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def scale_of(stack: SliceStack) -> float:
    return float(
        max(
            np.abs(stack.box_min).max(),
            np.abs(stack.box_max).max(),
            np.linalg.norm(stack.box_max - stack.box_min),
        )
    )


def check_invariants(stack: SliceStack) -> None:
    """Every documented property of a stack, each against an independent computation."""
    n, lo, hi = stack.view_dir, stack.box_min, stack.box_max
    tol = 1e-9 * scale_of(stack)
    assert np.isclose(np.linalg.norm(n), 1.0)
    assert stack.vertices.shape == (len(stack), 6, 3)
    assert np.all((stack.counts >= 3) & (stack.counts <= 6))
    # on the lattice
    lattice = stack.anchor @ n + stack.lattice_indices * stack.spacing
    assert np.all(np.abs(stack.depths - lattice) <= tol)
    # padding repeats the last real vertex
    for verts, count in zip(stack.vertices, stack.counts, strict=True):
        assert np.all(verts[count:] == verts[count - 1])
    right, up = eye_basis(n)
    for count in np.unique(stack.counts):  # polygons with the same vertex count, all at once
        chosen = stack.counts == count
        poly, depth = stack.vertices[chosen, :count], stack.depths[chosen]  # (m, c, 3), (m,)
        # on its plane
        assert np.all(np.abs(poly @ n - depth[:, None]) <= tol)
        # on the box surface
        assert np.all(poly >= lo - tol) and np.all(poly <= hi + tol)
        on_face = (np.abs(poly - lo) <= tol) | (np.abs(poly - hi) <= tol)
        assert np.all(on_face.any(axis=-1))
        # distinct vertices, convex and counter-clockwise seen from the eye
        p2 = np.stack([poly @ right, poly @ up], axis=-1)  # (m, c, 2)
        edges = np.roll(p2, -1, axis=1) - p2
        assert np.all(np.linalg.norm(edges, axis=-1) > 0)
        nxt = np.roll(edges, -1, axis=1)
        turns = edges[..., 0] * nxt[..., 1] - edges[..., 1] * nxt[..., 0]
        assert np.all(turns >= -tol * tol)
        heading = np.arctan2(edges[..., 1], edges[..., 0])
        turning = np.mod(np.roll(heading, -1, axis=1) - heading + np.pi, 2 * np.pi) - np.pi
        np.testing.assert_allclose(turning.sum(axis=1), 2 * np.pi)  # winds once, CCW: simple, convex
        x, y = p2[..., 0], p2[..., 1]
        assert np.all(np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y, axis=1) > 0)


def box_extent(lo, hi, n) -> tuple[float, float]:
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    d = corners @ (np.asarray(n, float) / np.linalg.norm(n))
    return float(d.min()), float(d.max())


def projected_area(lo, hi, n) -> float:
    """Area of the box's shadow on a plane perpendicular to n: no cross-section is larger."""
    a, b, c = np.asarray(hi, float) - np.asarray(lo, float)
    nx, ny, nz = np.abs(np.asarray(n, float)) / np.linalg.norm(n)
    return float(b * c * nx + a * c * ny + a * b * nz)


def areas_of(stack: SliceStack) -> np.ndarray:
    return np.array([shoelace(to_2d(p, stack.view_dir)) for p in stack.polygons()])


def triangle_areas(positions: np.ndarray) -> np.ndarray:
    tri = positions.reshape(-1, 3, 3).astype(np.float64)
    return 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)


# ------------------------------------------------------------------------------------- examples
@pytest.mark.parametrize("axis", [0, 1, 2])
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_axis_view_gives_face_sized_rectangles(axis, sign):
    """Looking along an axis, every slice is a rectangle with the area of the box face."""
    lo, hi = np.array([0.0, -1.0, 2.0]), np.array([2.0, 2.0, 6.0])
    n = np.zeros(3)
    n[axis] = sign
    stack = slice_polygons(lo, hi, n, 0.5)
    check_invariants(stack)
    size = hi - lo
    face = float(np.prod(np.delete(size, axis)))
    assert len(stack) == round(size[axis] / 0.5) + 1  # planes on both end faces included
    assert np.all(stack.counts == 4)
    np.testing.assert_allclose(areas_of(stack), face, rtol=1e-12)
    expected = np.arange(lo[axis], hi[axis] + 0.25, 0.5) * sign
    np.testing.assert_allclose(np.sort(stack.depths), np.sort(expected), atol=1e-12)


def test_diagonal_view_of_a_cube_gives_triangles_then_hexagons():
    """Along (1,1,1) the planes x+y+z=t cut triangles (t<1, t>2) and hexagons (1<t<2), with the
    exact areas sqrt(3)/2 t^2 and sqrt(3)/2 (t^2 - 3 (t-1)^2)."""
    stack = slice_polygons((0, 0, 0), (1, 1, 1), (1, 1, 1), SQRT3 / 10, back_to_front=False)
    check_invariants(stack)
    t = stack.depths * SQRT3  # x + y + z on each plane
    np.testing.assert_allclose(t, 0.3 * np.arange(1, 10), atol=1e-12)  # corner touches dropped
    assert list(stack.counts) == [3, 3, 3, 6, 6, 6, 3, 3, 3]
    tt = np.where(t > 1.5, 3.0 - t, t)  # symmetric about the centre
    exact = np.where(tt < 1, SQRT3 / 2 * tt**2, SQRT3 / 2 * (tt**2 - 3 * (tt - 1) ** 2))
    np.testing.assert_allclose(areas_of(stack), exact, rtol=1e-12)


def test_back_to_front_is_strictly_decreasing_depth():
    """Back to front means farthest (largest depth) first; front to back is the exact reverse."""
    args = ((-1, -2, 0.5), (3, 1, 2), (0.3, -0.5, 0.8), 0.07)
    back = slice_polygons(*args)
    front = slice_polygons(*args, back_to_front=False)
    assert len(back) > 10
    assert np.all(np.diff(back.depths) < 0)
    assert np.all(np.diff(front.depths) > 0)
    np.testing.assert_array_equal(back.depths, front.depths[::-1])
    np.testing.assert_array_equal(back.vertices, front.vertices[::-1])


def test_planes_are_anchored_when_the_view_turns():
    """Turning the view slightly keeps plane offsets from the anchor on the same k*spacing lattice."""
    lo, hi, spacing = (-1.0, -1.0, -1.0), (1.0, 2.0, 1.5), 0.05
    anchor = np.array([0.1234, -0.4, 0.25])
    n0 = np.array([0.2, 0.3, -1.0])
    a = math.radians(0.5)
    turn = np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
    ks = []
    for n in (n0, turn @ n0, turn @ turn @ n0):
        stack = slice_polygons(lo, hi, n, spacing, anchor=anchor)
        check_invariants(stack)
        k = (stack.depths - anchor @ stack.view_dir) / spacing
        np.testing.assert_allclose(k, np.round(k), atol=1e-9)
        np.testing.assert_array_equal(np.round(k), stack.lattice_indices)
        ks.append(set(stack.lattice_indices.tolist()))
    # the same planes persist (no sliding): nearly all lattice indices are shared between views
    assert len(ks[0] & ks[1]) >= len(ks[0]) - 2 and len(ks[1] & ks[2]) >= len(ks[1]) - 2
    # plane k=0 passes through the anchor
    stack = slice_polygons(lo, hi, n0, spacing, anchor=anchor)
    zero = stack.polygons()[int(np.flatnonzero(stack.lattice_indices == 0)[0])]
    assert abs((zero.mean(axis=0) - anchor) @ stack.view_dir) < 1e-12


def test_default_anchor_is_the_world_origin():
    """Without an anchor, depths are multiples of the spacing measured from the origin."""
    stack = slice_polygons((0.31, 0.2, 0.1), (1.3, 1.1, 0.9), (1, 2, 3), 0.1)
    np.testing.assert_allclose(stack.depths, stack.lattice_indices * 0.1, atol=1e-12)


def test_slab_volumes_converge_to_the_box_volume():
    """Sum of areas * spacing -> box volume, within the Riemann bound spacing * total variation of
    the (unimodal) area function, <= 2 * max area * spacing."""
    lo, hi = np.array([0.0, 0.0, 0.0]), np.array([1.0, 2.0, 3.0])
    volume = 6.0
    errors = []
    for spacing in (0.2, 0.1, 0.05, 0.025, 0.0125):
        areas = areas_of(slice_polygons(lo, hi, (0.3, -0.7, 0.5), spacing))
        err = abs(areas.sum() * spacing - volume)
        assert err <= 2 * projected_area(lo, hi, (0.3, -0.7, 0.5)) * spacing
        errors.append(err)
    assert errors[-1] < 1e-3 * volume
    assert errors[-1] < errors[0] / 8


def test_triangle_fan_covers_each_polygon_exactly():
    """The fan's triangles add up to each polygon's area, keep the CCW winding and the draw order."""
    stack = slice_polygons((-1, 0, 0), (1, 1, 2), (0.4, 0.5, 0.6), 0.1)
    mesh = triangle_fan(stack)
    assert mesh.positions.dtype == np.float32 and mesh.texcoords.dtype == np.float32
    assert mesh.positions.shape == mesh.texcoords.shape == (3 * int(np.sum(stack.counts - 2)), 3)
    assert np.all(np.diff(mesh.slice_indices) >= 0)  # drawing order kept
    per_slice = np.bincount(
        mesh.slice_indices[::3], weights=triangle_areas(mesh.positions), minlength=len(stack)
    )
    np.testing.assert_allclose(per_slice, areas_of(stack), rtol=1e-5)
    tri = mesh.positions.reshape(-1, 3, 3).astype(np.float64)
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    assert np.all(normals @ stack.view_dir < 0)  # facing the eye


def test_texture_coordinates_map_the_box_to_the_unit_cube():
    """box_min -> 0, box_max -> 1, and texcoord * size + box_min is the position."""
    lo, hi = np.array([-1.0, 2.0, 0.0]), np.array([3.0, 3.0, 0.5])
    stack = slice_polygons(lo, hi, (0, 0, 1), 0.25)  # planes at z = 0, 0.25, 0.5
    mesh = triangle_fan(stack)
    assert np.all(mesh.texcoords >= 0) and np.all(mesh.texcoords <= 1)
    np.testing.assert_allclose(mesh.texcoords * (hi - lo) + lo, mesh.positions, atol=1e-6)
    corners_tex = {tuple(t) for t in mesh.texcoords.tolist()}
    assert (0.0, 0.0, 0.0) in corners_tex and (1.0, 1.0, 1.0) in corners_tex
    assert {t[2] for t in corners_tex} == {0.0, 0.5, 1.0}


def test_sample_distance_along_ray():
    """spacing on the central ray, spacing / cos(theta) off axis, vectorized over rays."""
    n = np.array([0.0, 0.0, -2.0])  # need not be unit
    assert sample_distance_along_ray(0.1, n, n) == pytest.approx(0.1, rel=1e-15)
    thetas = np.radians([0.0, 10.0, 30.0, 60.0])
    rays = np.stack([np.sin(thetas), np.zeros_like(thetas), -np.cos(thetas)], axis=1) * 3.0
    np.testing.assert_allclose(sample_distance_along_ray(0.1, n, rays), 0.1 / np.cos(thetas), rtol=1e-14)
    assert sample_distance_along_ray(0.1, n, rays.reshape(2, 2, 3)).shape == (2, 2)


# ------------------------------------------------------------------------------------ hypothesis
coord = st.floats(-10, 10, allow_nan=False)
size = st.floats(0.05, 10, allow_nan=False)
component = st.floats(-1, 1, allow_nan=False)


@settings(max_examples=60, deadline=None)
@given(
    lo=st.tuples(coord, coord, coord),
    sz=st.tuples(size, size, size),
    d=st.tuples(component, component, component),
    slices=st.floats(1.0, 120.0),
    back=st.booleans(),
)
@example(
    lo=(0.0, 0.0, 0.0), sz=(1.0, 1.0, 1.0), d=(0.0, 1.0, 1.0), slices=1.0, back=False
)  # edge touches only
@example(lo=(0.0, 0.0, 0.0), sz=(1.0, 1.0, 1.0), d=(1.0, 1.0, 1.0), slices=3.0, back=True)  # through corners
def test_random_boxes_and_views(lo, sz, d, slices, back):
    """Random boxes and unit view directions: all invariants, slice count and volume bound hold."""
    n = np.asarray(d)
    assume(np.linalg.norm(n) > 1e-3)
    lo = np.asarray(lo)
    hi = lo + np.asarray(sz)
    dmin, dmax = box_extent(lo, hi, n)
    extent = dmax - dmin
    spacing = extent / slices
    stack = slice_polygons(lo, hi, n, spacing, back_to_front=back)
    check_invariants(stack)
    depth_steps = np.diff(stack.depths)
    assert np.all(depth_steps < 0) if back else np.all(depth_steps > 0)
    # count: floor(extent/spacing) .. ceil(extent/spacing)+1, less any end plane that only touches
    # a corner or an edge exactly (such planes are dropped as degenerate)
    touching = sum(abs(v / spacing - round(v / spacing)) < 1e-9 for v in (dmin, dmax))
    assert math.floor(extent / spacing) - touching <= len(stack) <= math.ceil(extent / spacing) + 1
    # volume: Riemann bound of a unimodal area function (see the convergence test)
    areas = areas_of(stack)
    bound = 2 * projected_area(lo, hi, n) * spacing
    assert abs(areas.sum() * spacing - np.prod(hi - lo)) <= bound * (1 + 1e-9)
    # triangle fan covers each polygon
    mesh = triangle_fan(stack)
    per_slice = np.bincount(
        mesh.slice_indices[::3], weights=triangle_areas(mesh.positions), minlength=len(stack)
    )
    np.testing.assert_allclose(per_slice, areas, rtol=1e-4, atol=1e-6 * scale_of(stack) ** 2)


# --------------------------------------------------------------------------------------- errors
@pytest.mark.parametrize(
    "kwargs, words",
    [
        ({"box_max": (1, 0, 1)}, "box_max > box_min"),
        ({"box_max": (1, -1, 1)}, "box_max > box_min"),
        ({"box_min": (0, float("nan"), 0)}, "box_min"),
        ({"box_min": (0, 0)}, "box_min"),
        ({"view_dir": (0, 0, 0)}, "view_dir"),
        ({"view_dir": (0, float("inf"), 1)}, "view_dir"),
        ({"spacing": 0.0}, "spacing"),
        ({"spacing": -0.1}, "spacing"),
        ({"spacing": float("nan")}, "spacing"),
        ({"spacing": 1.7 / (MAX_SLICES + 10)}, "slices"),
        ({"anchor": (0, 0, float("nan"))}, "anchor"),
    ],
)
def test_bad_inputs_raise_volren_error(kwargs, words):
    """Degenerate boxes, directions, spacings and anchors are refused with a one-line message."""
    args = {"box_min": (0, 0, 0), "box_max": (1, 1, 1), "view_dir": (1, 1, 1), "spacing": 0.1} | kwargs
    with pytest.raises(VolrenError, match=words):
        slice_polygons(**args)


def test_a_fine_but_reasonable_spacing_is_accepted():
    """Just under the slice limit still works (the limit is about mistakes, not fine sampling)."""
    stack = slice_polygons((0, 0, 0), (1, 1, 1), (0, 0, 1), 1.0 / (MAX_SLICES - 10))
    assert len(stack) == MAX_SLICES - 9


@pytest.mark.parametrize(
    "spacing, ray",
    [(0.0, (0, 0, 1)), (0.1, (0, 0, 0)), (0.1, (1, 0, 0)), (0.1, (0, 0, -1)), (0.1, (0, float("nan"), 1))],
)
def test_sample_distance_rejects_bad_rays(spacing, ray):
    """Zero spacing, null rays and rays parallel to or away from the slices are errors."""
    with pytest.raises(VolrenError):
        sample_distance_along_ray(spacing, (0, 0, 1), ray)
