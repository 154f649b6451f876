"""The renderers' numba camera rays against the model's definition, `Camera.rays`."""

from __future__ import annotations

import numpy as np
import pytest

from volren.kernels.camera_rays import image_rays, pixel_rays
from volren.model.camera import Camera


@pytest.mark.parametrize("parallel", [False, True])
def test_pixel_rays_equal_the_cameras(parallel):
    camera = Camera.orbit((0, 10, -3, 20, 0, 5), 30, 20, 1.2, parallel=parallel, aspect=1.5)
    rng = np.random.default_rng(7)
    x, y = rng.uniform(-3, 63, (4, 9)), rng.uniform(-3, 43, (4, 9))
    origins, directions = pixel_rays(camera, 60, 40, x, y)
    want_origins, want_directions = camera.rays(60, 40, x, y)
    assert origins.shape == directions.shape == (4, 9, 3)
    np.testing.assert_allclose(origins, want_origins, rtol=0, atol=1e-12)
    np.testing.assert_allclose(directions, want_directions, rtol=0, atol=1e-12)
    one_origin, one_direction = pixel_rays(camera, 60, 40, 5, 7.5)  # scalars, as picking asks
    assert one_origin.shape == one_direction.shape == (3,)
    np.testing.assert_allclose(one_direction, camera.rays(60, 40, 5, 7.5)[1], rtol=0, atol=1e-12)


def test_image_rays_are_row_major_pixel_centres():
    camera = Camera.orbit((0, 1, 0, 2, 0, 3), 40, -10, 1.0)
    origins, directions = image_rays(camera, 7, 5)
    want_origins, want_directions = camera.pixel_rays(7, 5)
    assert origins.shape == (35, 3)
    np.testing.assert_allclose(origins, want_origins.reshape(-1, 3), rtol=0, atol=1e-12)
    np.testing.assert_allclose(directions, want_directions.reshape(-1, 3), rtol=0, atol=1e-12)
