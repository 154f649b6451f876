"""The camera against VTK's own: view and projection matrices equal to 1e-9."""

from __future__ import annotations

import numpy as np
import pytest

from volren.errors import VolrenError
from volren.model.camera import Camera

BOUNDS = [
    (0.0, 67.0, 0.0, 67.0, 0.0, 67.0),  # ironProt
    (0.0, 255.0, 0.0, 255.0, 0.0, 127.0),  # engine
    (-1.0, 1.0, -1.0, 1.0, -1.0, 1.0),
    (0.0, 188.0, 0.0, 244.0, 0.0, 164.0),  # HeadMR (4 mm spacing)
    (3.0, 3.5, -100.0, 100.0, 0.0, 1e-3),  # thin and flat
]
VIEWS = [
    (0.0, 0.0, 1.0, False, 1.0),
    (30.0, 20.0, 1.0, False, 1.0),
    (30.0, 45.0, 1.3, False, 1.0),
    (30.0, 20.0, 1.4, True, 1.0),
    (-120.0, 80.0, 2.5, False, 1.5),
    (10.0, -60.0, 0.7, False, 0.6),
    (0.0, 90.0, 1.0, False, 1.0),
    (200.0, -90.0, 3.0, True, 0.5),
]


def vtk_matrices(bounds, azimuth, elevation, zoom, parallel, aspect):
    """vtkCamera after vtkRenderer.ResetCamera, Azimuth, Elevation, Zoom, ResetCameraClippingRange."""
    from vtkmodules import vtkRenderingCore as vtk_core

    renderer = vtk_core.vtkRenderer()
    renderer.SetNearClippingPlaneTolerance(0.001)  # what VTK picks for a 24-bit depth buffer
    camera = renderer.GetActiveCamera()
    camera.SetParallelProjection(parallel)
    # ResetCamera reads the aspect from the viewport: give the renderer one of that shape.
    window = vtk_core.vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetSize(int(round(300 * aspect)), 300)
    window.AddRenderer(renderer)
    renderer.ResetCamera(*bounds)
    camera.Azimuth(azimuth)
    camera.Elevation(elevation)
    camera.Zoom(zoom)
    renderer.ResetCameraClippingRange(*bounds)
    aspect = window.GetSize()[0] / window.GetSize()[1]

    def as_array(m):
        return np.array([[m.GetElement(i, j) for j in range(4)] for i in range(4)])

    view = as_array(camera.GetViewTransformMatrix())
    projection = as_array(camera.GetProjectionTransformMatrix(aspect, -1, 1))
    return view, projection, aspect


@pytest.mark.parametrize("bounds", BOUNDS)
@pytest.mark.parametrize("view", VIEWS)
def test_matrices_equal_vtk(bounds, view):
    azimuth, elevation, zoom, parallel, aspect = view
    vtk_view, vtk_projection, aspect = vtk_matrices(bounds, *view)
    camera = Camera.orbit(bounds, azimuth, elevation, zoom, parallel, aspect)
    np.testing.assert_allclose(camera.view_matrix(), vtk_view, rtol=0, atol=1e-9)
    np.testing.assert_allclose(camera.projection_matrix(aspect), vtk_projection, rtol=0, atol=1e-9)


def test_reset_fits_the_bounding_sphere():
    camera = Camera().reset((0, 2, 0, 2, 0, 2))
    radius = np.sqrt(3.0)
    assert np.allclose(camera.focal_point, (1, 1, 1))
    assert np.isclose(camera.distance, radius / np.sin(np.radians(15.0)))
    assert np.allclose(camera.direction, (0, 0, -1))


def test_pixel_rays_go_through_pixel_centres():
    camera = Camera.orbit((0, 10, 0, 10, 0, 10), 0, 0, 1, parallel=True)
    origins, directions = camera.pixel_rays(4, 2)
    assert origins.shape == directions.shape == (2, 4, 3)
    assert np.allclose(directions, (0, 0, -1))
    # Parallel projection: neighbouring pixel centres are one pixel apart in world units.
    pixel = 2 * camera.parallel_scale / 2
    assert np.allclose(np.diff(origins[0, :, 0]), pixel)
    assert origins[0, 0, 1] > origins[1, 0, 1]  # row 0 is the top


@pytest.mark.parametrize("parallel", [False, True])
def test_rays_start_on_the_near_plane_through_their_pixel(parallel):
    """The forward matrices map each ray's origin to its pixel centre at NDC depth -1 and a point
    further along it to the same pixel; perspective rays leave the eye."""
    camera = Camera.orbit((0, 10, -3, 20, 0, 5), 30, 20, 1.2, parallel=parallel, aspect=1.5)
    width, height = 60, 40
    rng = np.random.default_rng(3)
    x, y = rng.uniform(-2, width + 2, (5, 7)), rng.uniform(-2, height + 2, (5, 7))
    origins, directions = camera.rays(width, height, x, y)
    assert origins.shape == directions.shape == (5, 7, 3)
    np.testing.assert_allclose(np.linalg.norm(directions, axis=-1), 1.0, rtol=0, atol=1e-12)
    matrix = camera.projection_matrix(width / height) @ camera.view_matrix()
    for points, depth in ((origins, -1.0), (origins + 3.0 * directions, None)):
        clip = np.concatenate([points, np.ones((5, 7, 1))], axis=-1) @ matrix.T
        ndc = clip[..., :3] / clip[..., 3:]
        np.testing.assert_allclose((ndc[..., 0] + 1) / 2 * width - 0.5, x, rtol=0, atol=1e-9)
        np.testing.assert_allclose((1 - ndc[..., 1]) / 2 * height - 0.5, y, rtol=0, atol=1e-9)
        if depth is not None:
            np.testing.assert_allclose(ndc[..., 2], depth, rtol=0, atol=1e-9)
    if not parallel:
        toward = origins - np.asarray(camera.position)
        np.testing.assert_allclose(
            directions, toward / np.linalg.norm(toward, axis=-1, keepdims=True), atol=1e-12
        )
    one_origin, one_direction = camera.rays(
        width, height, x[2, 3], y[2, 3]
    )  # a scalar pixel, as picking asks
    assert one_origin.shape == (3,)
    np.testing.assert_allclose(one_direction, directions[2, 3], rtol=0, atol=1e-12)
    row_origins, _ = camera.rays(width, height, x[0], 17.0)  # broadcast: one row
    np.testing.assert_allclose(
        row_origins, camera.rays(width, height, x[0], np.full(7, 17.0))[0], rtol=0, atol=0
    )


def test_operations_are_rigid_and_invertible():
    camera = Camera.orbit((0, 10, 0, 20, 0, 5), 30, 20, 1.2)
    back = camera.azimuth(40).azimuth(-40)
    assert np.allclose(back.position, camera.position)
    assert np.isclose(camera.elevation(25).distance, camera.distance)
    assert np.isclose(camera.dolly(2.0).distance, camera.distance / 2)
    moved = camera.pan(1.0, 2.0)
    assert np.allclose(
        np.subtract(moved.position, moved.focal_point), np.subtract(camera.position, camera.focal_point)
    )


def test_round_trip_and_validation():
    camera = Camera.orbit((0, 1, 0, 1, 0, 1), 10, 20, 1.5, parallel=True)
    assert Camera.from_dict(camera.to_dict()) == camera
    with pytest.raises(VolrenError, match="coincide"):
        Camera(position=(0, 0, 0), focal_point=(0, 0, 0))
    with pytest.raises(VolrenError, match="view angle"):
        Camera(view_angle=0)
    with pytest.raises(VolrenError, match="unknown camera keys"):
        Camera.from_dict({"positoin": [0, 0, 1]})
    with pytest.raises(VolrenError, match="bounds"):
        Camera().reset((0, 1, 0, float("nan"), 0, 1))


@pytest.mark.parametrize(
    "fields, message",
    [
        ({"view_up": [0, 0, 0]}, "camera view up is the zero vector"),
        ({"view_up": [0, 0, 2]}, "camera view up [0.0, 0.0, 2.0] is along the view direction"),
        ({"position": [1e200, 0, 5]}, "camera position [1e+200, 0.0, 5.0] lies beyond 1e+18 from the origin"),
        ({"focal_point": [0, -1e19, 0]}, "camera focal point [0.0, -1e+19, 0.0] lies beyond 1e+18"),
        ({"view_up": ["0", "1", "0"]}, "camera view up must be 3 numbers, got ['0', '1', '0']"),
        ({"view_angle": "30"}, "camera view angle must be a number, got '30'"),
        ({"parallel": 1}, "camera parallel must be true or false, got 1"),
        ({"clipping_range": [0.1, True]}, "camera clipping range must be 2 numbers"),
    ],
)
def test_camera_dicts_that_draw_nothing_sensible_are_refused(fields, message):
    with pytest.raises(VolrenError) as info:
        Camera.from_dict({"position": [0, 0, 5], "focal_point": [0, 0, 0], **fields})
    assert message in str(info.value)
