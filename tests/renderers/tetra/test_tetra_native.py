"""tetra's C walk draws numba's image: hard cases (rays along edges and through vertices, holes,
transparent shells jumped over, a non-convex mesh, the eye inside the mesh, every blend mode,
shading, clip planes with cut faces, one length layer, early termination, adaptive refinement),
each drawn by both walks and compared to float rounding with the same cell counts; and the C
build's own rules (the planes bit for bit, the fallback, one-line failures)."""

from __future__ import annotations

import numpy as np
import pytest

from tests.renderers.tetra.test_tetra import SIZE, cube_grid, ramp, render, shell_cameras, shells
from volren.kernels import native
from volren.kernels.tet_planes import packed_face_planes
from volren.model.camera import Camera
from volren.model.clip_region import ClipPlane, ClipRegion
from volren.model.volume import TetVolume
from volren.renderers.tetra import walk_native

#: The walks differ only in how alpha is computed (1 - exp against expm1: 1e-16 apart) and in the
#: order of the colour table's sums: measured at most 3e-17 on the shared meshes.
ATOL = 1e-9
#: What both walks must count alike.
COUNTED = ("cell_steps", "cells_integrated", "rays_hit", "walks_cut", "entries_dropped")


@pytest.fixture(autouse=True)
def _needs_c() -> None:
    if not walk_native.available(1):
        pytest.skip("no C compiler here: numba's walk draws")


def both(mesh, tf, camera, size=SIZE, **settings):
    """(numba's image, C's image), after checking that their counters agree."""
    options = {"backend": "cpu", **settings.pop("options", {})}
    with walk_native.numba_only():
        expected, expected_counters = render("tetra", mesh, tf, camera, size, options=options, **settings)
    image, counters = render("tetra", mesh, tf, camera, size, options=options, **settings)
    for name in COUNTED:
        assert counters[name] == expected_counters[name], name
    return expected, image


def non_convex() -> TetVolume:
    """A 5^3 cube grid with a slot cut through it and a cavity inside: rays leave and re-enter."""
    mesh, _ = cube_grid(5, "five", field=lambda x, y, z: np.sin(x) + y * z / 5.0)
    centres = mesh.points[mesh.tets].mean(axis=1)
    slot = (np.abs(centres[:, 0] - 2.5) < 0.6) & (centres[:, 2] > 2.0)
    cavity = np.linalg.norm(centres - [2.5, 2.5, 1.2], axis=1) < 0.9
    return TetVolume(mesh.points, mesh.tets[~(slot | cavity)], mesh.values)


@pytest.mark.parametrize("scheme", ["kuhn", "five"])
@pytest.mark.parametrize("mode", ["composite", "maximum", "minimum", "average"])
def test_every_blend_mode_on_both_tessellations(scheme, mode):
    mesh, grid = cube_grid(4, scheme)
    tf = ramp(*grid.value_range)
    expected, image = both(mesh, tf, Camera.orbit(grid.bounds, 30, 20, 1.0), blend_mode=mode)
    assert image[..., 3].max() > 0.1
    assert np.abs(image - expected).max() <= ATOL


@pytest.mark.parametrize("view", ["perspective", "along_edges"])
def test_rays_along_edges_and_jumps_over_transparent_shells(view):
    mesh, tf = shells()
    camera, size = shell_cameras(mesh)[view]
    for skip in (True, False):
        expected, image = both(mesh, tf, camera, size, options={"skip_transparent": skip})
        assert image[..., 3].max() > 0.3
        assert np.abs(image - expected).max() <= ATOL


def test_a_non_convex_mesh_with_a_hole_and_nan_cells_and_the_eye_inside():
    mesh = non_convex()
    values = mesh.values.copy()
    values[np.argmin(np.linalg.norm(mesh.points - [1.0, 1.0, 1.0], axis=1))] = np.nan
    holed = TetVolume(mesh.points, mesh.tets, values)
    tf = ramp(-1.0, 6.0)
    for camera in (Camera.orbit(holed.bounds, 35, 25, 1.0), Camera.orbit(holed.bounds, 80, -10, 4.0)):
        expected, image = both(holed, tf, camera)
        assert image[..., 3].max() > 0.1
        assert np.abs(image - expected).max() <= ATOL


def test_shading_clip_planes_cut_faces_one_layer_and_termination():
    mesh, grid = cube_grid(4, "kuhn")
    tf = ramp(*grid.value_range)
    camera = Camera.orbit(grid.bounds, 30, 20, 1.0)
    clip = ClipRegion((ClipPlane((2.0, 2.0, 2.0), (1.0, 0.3, -0.2)),), (0.5, 3.6, 0.0, 4.0, 0.2, 3.0), True)
    cases = [
        {"shade": True},
        {"clip": clip},
        {"clip": clip, "shade": True},
        {"options": {"table_lengths": 1, "table_size": 7}},
        {"options": {"termination_alpha": 0.5}},
    ]
    for settings in cases:
        expected, image = both(mesh, tf, camera, **settings)
        assert image[..., 3].max() > 0.1
        assert np.abs(image - expected).max() <= ATOL, settings


@pytest.mark.parametrize("stride", [1, 8])
def test_the_eye_inside_the_mesh(stride):
    """Rays that start in the cells the near plane cuts (listed per pixel), with boundary faces behind the
    eye (covering every pixel), a ray per pixel and refined."""
    mesh, grid = cube_grid(4, "kuhn")
    camera = Camera(position=(2.1, 1.9, 1.2), focal_point=(2.0, 2.0, 4.0), view_angle=60.0,
                    clipping_range=(0.05, 20.0))  # fmt: skip
    expected, image = both(mesh, ramp(*grid.value_range), camera, 64,
                           options={"image_stride": stride, "refine_tolerance": 0.0})  # fmt: skip
    assert image[..., 3].min() > 0.05  # every ray starts in the mesh
    assert np.abs(image - expected).max() <= ATOL


def test_adaptive_refinement_casts_the_same_rays():
    mesh, grid = cube_grid(4, "five")
    tf = ramp(*grid.value_range)
    expected, image = both(mesh, tf, Camera.orbit(grid.bounds, 10, 40, 1.2), 61,
                           options={"image_stride": 4, "refine_tolerance": 0.02})  # fmt: skip
    assert np.abs(image - expected).max() <= ATOL


def test_the_planes_are_numbas_bit_for_bit():
    """Both cells of a face must get exactly opposite planes (the walk's watertightness): the C
    planes equal numba's, whose property the mesh tests check."""
    mesh = non_convex()
    rng = np.random.default_rng(5)
    points = mesh.points + rng.normal(scale=0.2, size=mesh.points.shape)
    tets = np.ascontiguousarray(mesh.tets, dtype=np.int64)
    tets[3] = tets[3, [0, 0, 1, 2]]  # a flat cell: zero normals
    planes = walk_native.packed_planes(points, tets)
    assert planes is not None
    assert np.array_equal(planes, packed_face_planes(points, tets))
    with pytest.raises(ValueError, match="cell corners must index the points"):
        walk_native.packed_planes(points, tets + len(points))


def test_off_means_numba(monkeypatch):
    monkeypatch.setenv("VOLREN_NATIVE", "0")
    assert not walk_native.available(10)
    assert walk_native.packed_planes(np.zeros((4, 3)), np.array([[0, 1, 2, 3]])) is None
    with walk_native.numba_only():
        monkeypatch.setenv("VOLREN_NATIVE", "1")
        assert not walk_native.available(10)
    assert walk_native.available(10) and not walk_native.available(2**31)


def test_the_portable_build_draws_the_same(monkeypatch, tmp_path):
    """A CPU without AVX2 gets walk.c built without its vector exit test: the same walk."""
    monkeypatch.setenv("VOLREN_NATIVE_CACHE", str(tmp_path))
    monkeypatch.setattr(native, "cpu_has_vector_units", lambda: False)
    native._load.cache_clear()
    try:
        mesh, tf = shells()
        camera, size = shell_cameras(mesh)["along_edges"]
        expected, image = both(mesh, tf, camera, size)
        assert image[..., 3].max() > 0.3
        assert np.abs(image - expected).max() <= ATOL
        assert [p.name.startswith("walk-") for p in tmp_path.glob("*.so")] == [True]
    finally:
        native._load.cache_clear()
