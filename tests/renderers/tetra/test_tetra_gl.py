"""`tetra`'s GL walk (compute shaders; Mesa llvmpipe here) against its CPU walk and the reference.

The two walks implement the same traversal, one in float64 and one in float32, so they agree to
float32 rounding on every scene here: convex and non-convex meshes, rays through vertices and
edges, holes, shading, every blend mode, an eye inside the mesh, entry lists that must grow."""

from __future__ import annotations

import numpy as np
import pytest

from tests.renderers.analytic import box_path_lengths, homogeneous_image, rmse
from tests.renderers.tetra.test_tetra import cube_grid, ramp, render, shell_cameras, shells
from volren.api import prepared_renderer
from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.settings import RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import TetVolume
from volren.renderers.tetra import gl_walk

pytestmark = pytest.mark.usefixtures("opengl")  # fails, naming the packages, where EGL cannot work

GL = {"backend": "gl"}
CPU = {"backend": "cpu"}


def both(volume, tf, camera, size=48, options=None, **settings):
    """(GL image, CPU image, GL counters, CPU counters)."""
    gl, gl_counters = render("tetra", volume, tf, camera, size, options={**GL, **(options or {})}, **settings)
    cpu, cpu_counters = render(
        "tetra", volume, tf, camera, size, options={**CPU, **(options or {})}, **settings
    )
    return gl, cpu, gl_counters, cpu_counters


@pytest.fixture(scope="module")
def kuhn():
    mesh, grid = cube_grid(4, "kuhn")
    return mesh, ramp(*grid.value_range), Camera.orbit(grid.bounds, 30, 20, 1.0)


def test_the_gl_walk_matches_the_cpu_walk(kuhn):
    mesh, tf, camera = kuhn
    gl, cpu, gl_counters, cpu_counters = both(mesh, tf, camera)
    assert cpu[..., 3].max() > 0.5
    assert np.abs(gl - cpu).max() < 2e-4
    assert np.array_equal(gl[..., 3] > 1e-3, cpu[..., 3] > 1e-3)
    assert gl_counters["rays_hit"] == cpu_counters["rays_hit"]
    # the same cells, give or take zero-length steps at edges rounded differently
    assert abs(gl_counters["cell_steps"] - cpu_counters["cell_steps"]) <= 0.01 * cpu_counters["cell_steps"]
    assert gl_counters["walks_cut"] == 0 and gl_counters["gpu_ms"] >= 0  # llvmpipe's timer reads ~0


def test_a_mesh_far_from_the_origin_keeps_its_precision(kuhn):
    """Coordinates near 1e5 leave float32 about 0.008 of resolution; the GL walk works relative to
    the mesh's centre, so the image is the same as at the origin."""
    mesh, tf, _ = kuhn
    far = TetVolume(mesh.points + 1e5, mesh.tets, mesh.values)
    camera = Camera.orbit(far.bounds, 30, 20, 1.0)
    gl, cpu, _, _ = both(far, tf, camera)
    assert np.abs(gl - cpu).max() < 2e-4


@pytest.mark.parametrize("scheme", ["kuhn", "five"])
def test_rays_through_vertices_and_edges(scheme):
    """test_tetra's constructed case: every ray runs along edges or through vertices."""
    n = 3
    mesh, _ = cube_grid(n, scheme, field=lambda x, y, z: 0 * x + 5.0)
    tf = TransferFunction1D(color=[[0, 0.2, 0.9, 0.5]], opacity=[[0, 0.3]], opacity_unit_distance=1.5)
    pixels = 2 * n + 1
    camera = Camera(
        position=(1.5, 1.5, 10.0),
        focal_point=(1.5, 1.5, 1.5),
        parallel=True,
        parallel_scale=n * pixels / (pixels - 1) / 2.0,
        clipping_range=(1.0, 20.0),
    )
    image, counters = render("tetra", mesh, tf, camera, pixels, options=GL)
    expected = homogeneous_image(
        box_path_lengths(camera, pixels, pixels, mesh.bounds), (0.2, 0.9, 0.5), 0.3, 1.5
    )
    assert np.isfinite(image).all() and counters["walks_cut"] == 0
    assert np.abs(image[1:-1, 1:-1] - expected[1:-1, 1:-1]).max() < 1e-4


def test_rays_along_axes_at_an_angle_of_the_grid():
    """A perspective view straight down a row of vertices: the central ray runs along a line of edges."""
    mesh, _ = cube_grid(3, "five", field=lambda x, y, z: 0 * x + 5.0)
    tf = TransferFunction1D(color=[[0, 0.2, 0.9, 0.5]], opacity=[[0, 0.3]], opacity_unit_distance=1.5)
    camera = Camera(
        position=(1.0, 2.0, 12.0), focal_point=(1.0, 2.0, 1.5), view_angle=30.0, clipping_range=(1.0, 30.0)
    )
    gl, cpu, gl_counters, _ = both(mesh, tf, camera, 33)
    assert gl_counters["walks_cut"] == 0
    assert np.abs(gl - cpu).max() < 2e-4


def test_holes_and_non_convex_meshes():
    """A NaN vertex punches a hole: rays leave the mesh and re-enter behind it."""
    holed = holed_mesh()
    tf = TransferFunction1D(color=[[0, 1, 1, 1]], opacity=[[0, 0.2], [4, 0.2]])
    camera = Camera.orbit(holed.bounds, 10, 10, 1.0)
    gl, cpu, _, _ = both(holed, tf, camera)
    reference, _ = render("reference", holed, tf, camera)
    assert np.abs(gl - cpu).max() < 2e-4
    assert rmse(gl, reference) < 5e-4


@pytest.mark.parametrize("mode", ["maximum", "minimum", "average"])
def test_projections(kuhn, mode):
    mesh, tf, camera = kuhn
    gl, cpu, _, _ = both(mesh, tf, camera, blend_mode=mode)
    assert np.abs(gl - cpu).max() < 1e-4


def test_shading(kuhn):
    mesh, tf, camera = kuhn
    gl, cpu, _, _ = both(mesh, tf, camera, shade=True)
    plain, _ = render("tetra", mesh, tf, camera, options=GL)
    assert np.abs(gl - plain).max() > 0.01  # shading changed the image
    assert np.abs(gl - cpu).max() < 2e-4


def test_early_termination_and_transparent_cells(kuhn):
    mesh, _, camera = kuhn
    opaque = TransferFunction1D(color=[[0, 1, 1, 1]], opacity=[[0, 0.0], [10, 0.0], [11, 1.0], [24, 1.0]])
    gl_all, cpu_all, counters_all, _ = both(mesh, opaque, camera, options={"termination_alpha": 1.0})
    gl_stop, _, counters_stop, _ = both(mesh, opaque, camera, options={"termination_alpha": 0.99})
    assert np.abs(gl_all - cpu_all).max() < 2e-4
    assert np.abs(gl_all - gl_stop).max() <= 0.01 + 1e-6
    assert counters_stop["cells_integrated"] < counters_all["cells_integrated"]
    gl_every, cpu_every, counters_every, _ = both(
        mesh, opaque, camera, options={"termination_alpha": 1.0, "skip_transparent": False}
    )
    # every step is integrated but the zero-length ones around edges
    assert counters_all["cells_integrated"] < counters_every["cells_integrated"]
    assert (
        counters_every["cell_steps"] - counters_every["cells_integrated"]
        <= 0.001 * counters_every["cell_steps"]
    )
    assert np.abs(gl_every - cpu_every).max() < 2e-4


@pytest.mark.parametrize("view", ["perspective", "along_edges"])
def test_rays_jump_over_transparent_cells(view):
    """test_tetra's shells: walking only the visible cells gives the image of the walk through
    every cell, on the GL walk as on the CPU walk."""
    mesh, tf = shells()
    camera, size = shell_cameras(mesh)[view]
    gl, cpu, gl_counters, cpu_counters = both(mesh, tf, camera, size)
    gl_every, _, every_counters, _ = both(mesh, tf, camera, size, options={"skip_transparent": False})
    assert cpu[..., 3].max() > 0.3
    assert np.abs(gl - cpu).max() < 2e-4
    assert np.array_equal(gl[..., 3] > 1e-3, cpu[..., 3] > 1e-3)
    assert np.abs(gl - gl_every).max() < 2e-4
    assert gl_counters["cell_steps"] < 0.9 * every_counters["cell_steps"]
    if view == "perspective":  # along the edges, float32 rounds the zero-length steps around them differently
        assert (
            abs(gl_counters["cell_steps"] - cpu_counters["cell_steps"]) <= 0.01 * cpu_counters["cell_steps"]
        )


def test_an_eye_inside_the_mesh(kuhn):
    """Rays start inside the cells the near plane cuts."""
    mesh, tf, _ = kuhn
    camera = Camera(
        position=(2.1, 1.9, 1.2), focal_point=(2.0, 2.0, 4.0), view_angle=60.0, clipping_range=(0.05, 20.0)
    )
    gl, cpu, _, _ = both(mesh, tf, camera)
    reference, _ = render("reference", mesh, tf, camera)
    assert cpu[..., 3].min() > 0.05  # every ray starts in the mesh
    assert np.abs(gl - cpu).max() < 2e-4
    assert rmse(cpu, reference) < 5e-4


def test_spx_against_the_cpu_walk_and_the_reference(shared_data):
    """spx is non-convex: rays leave and re-enter, many times."""
    from tests.conftest import load_scene_tf
    from volren.io import load_volume

    volume = load_volume(shared_data / "tets" / "spx.vtk", scalars="scalars")
    tf = load_scene_tf("spx-spiky")
    camera = Camera.orbit(volume.bounds, 30, 20, 1.0)
    gl, cpu, gl_counters, _ = both(volume, tf, camera, 64)
    reference, _ = render("reference", volume, tf, camera, 64)
    assert gl_counters["walks_cut"] == 0
    assert rmse(gl, cpu) < 2e-4
    assert rmse(gl, reference) < 3e-3
    # no holes or streaks: the same pixels as the CPU walk, whose segments are the reference's
    # (test_tetra); the table's blur of the spikes shows 4 faint pixels (alpha 0.01-0.08) on both
    assert np.array_equal(gl[..., 3] > 0.01, cpu[..., 3] > 0.01)


def holed_mesh() -> TetVolume:
    """3^3 Kuhn cubes with a NaN vertex at (1, 1, 1): its cells are a hole inside the mesh."""
    mesh, _ = cube_grid(3, "kuhn", field=lambda x, y, z: 0 * x + 2.0)
    values = mesh.values.copy()
    values[np.argmin(np.linalg.norm(mesh.points - 1.0, axis=1))] = np.nan
    return TetVolume(mesh.points, mesh.tets, values)


def test_the_entry_lists_grow(monkeypatch):
    """A convex mesh needs one slot per pixel (the fill rule gives each pixel centre one front
    face); rays through a hole meet more boundary faces, and the lists grow to hold them."""
    mesh = holed_mesh()
    tf = TransferFunction1D(color=[[0, 1, 1, 1]], opacity=[[0, 0.2], [4, 0.2]])
    camera = Camera.orbit(mesh.bounds, 10, 10, 1.0)
    expected, first = render("tetra", mesh, tf, camera, options=GL)
    assert first["entry_slots"] == gl_walk.SLOTS
    monkeypatch.setattr(gl_walk, "SLOTS", 1)
    image, counters = render("tetra", mesh, tf, camera, options=GL)
    assert counters["entry_slots"] > 1
    assert np.array_equal(image, expected)


def test_uploads_follow_the_tf_and_the_volume(kuhn):
    """The mesh goes up once per volume, the tables once per TF version, the entry faces once per set of
    visible cells; camera moves send none of them."""
    mesh, tf, camera = kuhn
    tf = tf.copy()
    with prepared_renderer("tetra", mesh, tf, RenderSettings(options=GL)) as renderer:
        renderer.render(camera, 16, 16)
        walk = renderer._gl
        tables, faces = walk._table, walk._faces
        mesh_planes = walk._mesh_buffers["planes"]
        renderer.render(Camera.orbit(mesh.bounds, 60, 10, 1.0), 16, 16)
        assert walk._table is tables and walk._mesh_buffers["planes"] is mesh_planes and walk._faces is faces
        tf.set_opacity_points([[0, 0.0], [24, 0.5]])  # every cell stays visible: the entry faces stay
        renderer.render(camera, 16, 16)
        assert walk._table is not tables and walk._mesh_buffers["planes"] is mesh_planes
        assert walk._faces is faces
        tf.set_opacity_points([[0, 0.0], [12, 0.0], [24, 0.5]])  # the entry faces are the visible cells' ones
        renderer.render(camera, 16, 16)
        assert walk._faces is not faces
        objects = len(walk.gl_objects)
        renderer.set_volume(TetVolume(mesh.points, mesh.tets, mesh.values * 2))
        renderer.render(camera, 16, 16)
        assert walk._mesh_buffers["planes"] is not mesh_planes
        assert len(walk.gl_objects) == objects  # old buffers freed
    assert walk.gl_objects == []


def test_options(kuhn):
    mesh, tf, camera = kuhn
    with pytest.raises(VolrenError, match="backend"):
        render("tetra", mesh, tf, camera, 8, options={"backend": "cuda"})
    with pytest.raises(VolrenError, match="cpu backend only"):
        render("tetra", mesh, tf, camera, 8, options={"backend": "gl", "image_stride": 4})


def test_auto_uses_the_cpu_on_a_software_rasterizer(kuhn):
    """`auto` takes the GL walk only on a hardware GPU (where it is faster; on llvmpipe numba is)."""
    mesh, tf, camera = kuhn
    _, counters = render("tetra", mesh, tf, camera, 8)
    assert ("gpu_ms" in counters) == (gl_walk.gpu_renderer() is not None)


def test_one_renderer_at_several_sizes(kuhn):
    """The frame's buffers follow the image size (growing, shrinking and growing again)."""
    mesh, tf, camera = kuhn
    with prepared_renderer("tetra", mesh, tf, RenderSettings(options=GL)) as renderer:
        images = {size: renderer.render(camera, size, size) for size in (16, 40, 16, 40)}
    for size, image in images.items():
        expected, _ = render("tetra", mesh, tf, camera, size, options=GL)
        assert np.array_equal(image, expected)
