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
    vtk_core = pytest.importorskip("vtkmodules.vtkRenderingCore")
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


def test_operations_are_rigid_and_invertible():
    camera = Camera.orbit((0, 10, 0, 20, 0, 5), 30, 20, 1.2)
    back = camera.azimuth(40).azimuth(-40)
    assert np.allclose(back.position, camera.position)
    assert np.isclose(camera.elevation(25).distance, camera.distance)
    assert np.isclose(camera.dolly(2.0).distance, camera.distance / 2)
    moved = camera.pan(1.0, 2.0)
    assert np.allclose(np.subtract(moved.position, moved.focal_point), np.subtract(camera.position, camera.focal_point))


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
