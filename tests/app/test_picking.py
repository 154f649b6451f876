"""Picking on analytic volumes (the picked point is known in closed form), and the viewport's
ctrl + click that starts it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from volren.app.core.picking import OPACITY_THRESHOLD, STEP_FRACTION, pick, pixel_ray, sample_grid
from volren.model.camera import Camera
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TFWidget, TransferFunction2D
from volren.model.volume import TetVolume, UniformVolume

N = 33  # grid points per axis over [-1, 1]: 0 is a grid point, the axes are grid lines
H = 2.0 / (N - 1)
STEP = STEP_FRACTION * H
RADIUS = 0.6  # the TF is opaque below this value
UNIT = 0.05  # opacity_unit_distance: a = 0.5 per UNIT, so the threshold is reached UNIT inside
SIZE = 101  # odd: the centre pixel's ray is the z axis


def grid(field) -> UniformVolume:
    axis = np.linspace(-1.0, 1.0, N)
    z, y, x = np.meshgrid(axis, axis, axis, indexing="ij")
    return UniformVolume(field(x, y, z), (H, H, H), (-1.0, -1.0, -1.0))


@pytest.fixture(scope="module")
def sphere() -> UniformVolume:
    """value = distance from the centre."""
    return grid(lambda x, y, z: np.sqrt(x * x + y * y + z * z))


def below(threshold: float, opacity: float = 0.5, unit: float = UNIT) -> TransferFunction1D:
    """Opacity `opacity` below `threshold`, 0 above (a step: duplicated control point)."""
    return TransferFunction1D(
        [[0.0, 1.0, 1.0, 1.0]], [[-5.0, opacity], [threshold, opacity], [threshold, 0.0], [5.0, 0.0]], unit
    )


@pytest.fixture(scope="module")
def camera(sphere) -> Camera:
    """VTK's default camera reset on the data: on +z looking down -z, +y up."""
    return Camera.orbit(sphere.bounds)


def test_pixel_ray_is_the_renderers_ray(camera):
    for cam in (
        camera.azimuth(30).elevation(20),
        camera.azimuth(-50).zoom(1.7),
        Camera.orbit((0, 2, 0, 1, 0, 1), 10, 5, 1, True),
    ):
        origins, dirs = cam.pixel_rays(40, 30)
        for x, y in ((0, 0), (39, 29), (17, 4), (5, 22)):
            o, d = pixel_ray(cam, x, y, 40, 30)
            np.testing.assert_allclose(o, origins[y, x], atol=1e-12)
            np.testing.assert_allclose(d, dirs[y, x], atol=1e-12)


def test_sample_grid_is_trilinear_with_central_difference_gradients():
    rng = np.random.default_rng(2)
    values = rng.normal(size=(5, 6, 7))
    volume = UniformVolume(values, (0.5, 1.0, 2.0), (1.0, -2.0, 0.5))
    gz, gy, gx = np.gradient(values, 2.0, 1.0, 0.5)
    # at grid points the interpolants are the samples themselves
    k, j, i = 3, 4, 6
    point = np.array([1.0 + 0.5 * i, -2.0 + 1.0 * j, 0.5 + 2.0 * k])
    value, grad = sample_grid(volume, point[None])
    assert value[0] == pytest.approx(values[k, j, i])
    np.testing.assert_allclose(grad[0], [gx[k, j, i], gy[k, j, i], gz[k, j, i]])
    # midway between two grid points along y: the mean of both
    point[1] += 0.5
    value, grad = sample_grid(volume, point[None])
    assert value[0] == pytest.approx(0.5 * (values[k, j, i] + values[k, j + 1, i]))
    np.testing.assert_allclose(grad[0], 0.5 * np.array([g[k, j, i] + g[k, j + 1, i] for g in (gx, gy, gz)]))


def test_centre_ray_picks_where_half_the_opacity_is_reached(sphere, camera):
    result = pick(sphere, below(RADIUS), camera, SIZE // 2, SIZE // 2, SIZE, SIZE)
    assert result is not None and result.rule == "opacity"
    assert result.opacity == OPACITY_THRESHOLD
    x, y, z = result.position
    assert abs(x) < 1e-12 and abs(y) < 1e-12
    # a = 0.5 per UNIT: the accumulated opacity reaches 0.5 exactly UNIT past the surface
    assert z == pytest.approx(RADIUS - UNIT, abs=STEP)
    assert result.value == pytest.approx(z, abs=1e-9)  # |z| is exactly linear between grid points
    assert result.gradient_magnitude == pytest.approx(1.0, abs=1e-12)


def test_oblique_ray_picks_on_the_sphere_along_the_known_ray(sphere, camera):
    px, py = 40, 58  # left of and below the centre, 0.45 from the axis at the focal plane
    o, d = pixel_ray(camera, px, py, SIZE, SIZE)
    b = float(o @ d)
    entry = -b - math.sqrt(b * b - (o @ o - RADIUS**2))  # ray-sphere intersection, nearer root
    result = pick(sphere, below(RADIUS), camera, px, py, SIZE, SIZE)
    assert result is not None and result.rule == "opacity"
    expected = o + (entry + UNIT) * d
    np.testing.assert_allclose(result.position, expected, atol=STEP + 1e-3)
    assert result.depth == pytest.approx(entry + UNIT, abs=STEP + 1e-3)
    r = float(np.linalg.norm(result.position))
    assert r < RADIUS
    assert result.value == pytest.approx(r, abs=2e-3)  # trilinear error of the distance field
    assert result.gradient_magnitude == pytest.approx(1.0, abs=0.02)


def test_a_2d_tf_picks_by_value_and_gradient(sphere, camera):
    box = TFWidget.box((0.0, RADIUS), (0.5, 1.5), (1.0, 1.0, 1.0), 0.5)
    tf = TransferFunction2D((0.0, 1.8), (0.0, 2.0), [box], UNIT)
    result = pick(sphere, tf, camera, SIZE // 2, SIZE // 2, SIZE, SIZE)
    assert result is not None and result.rule == "opacity"
    assert result.position[2] == pytest.approx(RADIUS - UNIT, abs=STEP)
    # the same values with gradients the box does not take: nothing visible, first sample in the data
    tf.replace_widget(0, TFWidget.box((0.0, RADIUS), (1.5, 2.0), (1.0, 1.0, 1.0), 0.5))
    result = pick(sphere, tf, camera, SIZE // 2, SIZE // 2, SIZE, SIZE)
    assert result is not None and result.rule == "first" and result.opacity == 0.0
    assert result.position[2] == pytest.approx(1.0 - STEP / 2, abs=1e-3)  # the box's face is z = 1


def test_faint_material_picks_the_strongest_contribution(sphere, camera):
    """Never reaching 0.5: the first piece inside the sphere adds the most (light arrives there first)."""
    result = pick(sphere, below(RADIUS, opacity=0.01, unit=1.0), camera, SIZE // 2, SIZE // 2, SIZE, SIZE)
    assert result is not None and result.rule == "strongest"
    assert RADIUS - STEP <= result.position[2] <= RADIUS
    assert 0.0 < result.opacity < 0.01 * STEP * 1.01


def test_misses_return_none(sphere, camera):
    assert pick(sphere, below(RADIUS), camera, 0, 0, SIZE, SIZE) is None  # beside the box
    assert pick(sphere, below(RADIUS), camera, SIZE, 3, SIZE, SIZE) is None  # outside the image
    assert pick(sphere, below(RADIUS), camera, -1, 3, SIZE, SIZE) is None


def test_rays_through_nan_cells_see_no_data(camera):
    volume = grid(lambda x, y, z: np.where(x <= 0.5, np.nan, x))
    assert pick(volume, below(RADIUS), camera, SIZE // 2, SIZE // 2, SIZE, SIZE) is None
    result = pick(volume, below(2.0), camera, 75, SIZE // 2, SIZE, SIZE)  # through 0.75 < x < 1
    assert result is not None and result.value > 0.5


# ---------------------------------------------------------------------------- tet meshes
def kuhn_mesh(n: int, field) -> TetVolume:
    """[-1, 1]^3 in n^3 cubes, six tets each, values field(points)."""
    axis = np.linspace(-1.0, 1.0, n + 1)
    z, y, x = np.meshgrid(axis, axis, axis, indexing="ij")
    points = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)
    tets = []
    for k in range(n):
        for j in range(n):
            for i in range(n):
                for path in ((0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)):
                    c = [i, j, k]
                    ids = [(c[2] * (n + 1) + c[1]) * (n + 1) + c[0]]
                    for axis_ in path:
                        c[axis_] += 1
                        ids.append((c[2] * (n + 1) + c[1]) * (n + 1) + c[0])
                    tets.append(ids)
    return TetVolume(points, np.asarray(tets), field(points))


def test_tet_mesh_pick_on_a_linear_field(camera):
    """value = z: linear in every tet, so the pick is exact up to the sampling step."""
    mesh = kuhn_mesh(4, lambda p: p[:, 2].copy())
    step = STEP_FRACTION * mesh.characteristic_length
    for px, py in ((SIZE // 2, SIZE // 2), (20, 70)):
        result = pick(mesh, below(RADIUS), camera, px, py, SIZE, SIZE)
        assert result is not None and result.rule == "opacity"
        o, d = pixel_ray(camera, px, py, SIZE, SIZE)
        entry = (RADIUS - o[2]) / d[2]  # where the ray crosses z = RADIUS
        np.testing.assert_allclose(result.position, o + (entry + UNIT) * d, atol=step)
        assert result.value == pytest.approx(result.position[2], abs=1e-9)
        assert result.gradient_magnitude == pytest.approx(1.0, abs=1e-9)
    assert pick(mesh, below(RADIUS), camera, 0, 0, SIZE, SIZE) is None


def test_tet_mesh_gaps_are_no_data(camera):
    """Drop the tets of the central column: the centre ray passes through a hole."""
    mesh = kuhn_mesh(4, lambda p: p[:, 2].copy())
    centres = mesh.points[mesh.tets].mean(axis=1)
    keep = ~((np.abs(centres[:, 0]) < 0.5) & (np.abs(centres[:, 1]) < 0.5))
    holed = TetVolume(mesh.points, mesh.tets[keep], mesh.values)
    assert pick(holed, below(RADIUS), camera, SIZE // 2, SIZE // 2, SIZE, SIZE) is None
    assert pick(holed, below(RADIUS), camera, 25, SIZE // 2, SIZE, SIZE) is not None  # -1 < x < -0.75


# ---------------------------------------------------------------------------- the viewport
@pytest.fixture
def viewport(qtbot, sphere, camera):
    from tests.app.widget_input import shown
    from volren.app.core.state import ViewState
    from volren.app.rendering.viewport import Viewport

    state = ViewState()
    state.load(sphere, below(RADIUS), camera.reset(sphere.bounds, 1.5))
    return shown(qtbot, Viewport(state), (300, 200))


def test_ctrl_click_emits_the_pixel_in_full_frame_coordinates(qtbot, viewport):
    from PyQt5.QtCore import QPoint, Qt

    camera = viewport._state.camera
    ratio = viewport.devicePixelRatioF()
    with qtbot.waitSignal(viewport.pointPicked, timeout=1000) as blocker:
        qtbot.mouseClick(viewport, Qt.LeftButton, Qt.ControlModifier, QPoint(125, 120))
    assert blocker.args == [math.floor(125.5 * ratio), math.floor(120.5 * ratio)]
    assert viewport._state.camera is camera  # no rotation
    with qtbot.assertNotEmitted(viewport.pointPicked):
        qtbot.mouseClick(viewport, Qt.LeftButton, Qt.NoModifier, QPoint(125, 120))


def test_plain_drag_still_rotates(qtbot, viewport):
    from PyQt5.QtCore import QPoint, Qt

    camera = viewport._state.camera
    # through the QWindow: Qt 5's QWidget mouseMove only moves the cursor (nothing arrives offscreen)
    window = viewport.window().windowHandle()

    def at(x: int, y: int) -> QPoint:
        return viewport.mapTo(viewport.window(), QPoint(x, y))

    with qtbot.assertNotEmitted(viewport.pointPicked):
        qtbot.mousePress(window, Qt.LeftButton, Qt.NoModifier, at(150, 100))
        qtbot.mouseMove(window, at(180, 110))
        qtbot.mouseRelease(window, Qt.LeftButton, Qt.NoModifier, at(180, 110))
    assert viewport._state.camera != camera


def test_a_ctrl_click_picks_the_point_under_the_mouse(qtbot, viewport):
    """What the main window wires up: pointPicked -> pick with the state's camera at pixel_size()."""
    from PyQt5.QtCore import QPoint, Qt

    state = viewport._state
    picked = []

    def on_pick(x: int, y: int) -> None:
        width, height = viewport.pixel_size()
        picked.append(pick(state.render_volume, state.transfer_function, state.camera, x, y, width, height))

    viewport.pointPicked.connect(on_pick)
    qtbot.mouseClick(viewport, Qt.LeftButton, Qt.ControlModifier, QPoint(150, 100))  # the middle
    assert picked and picked[0] is not None and picked[0].rule == "opacity"
    assert picked[0].position[2] == pytest.approx(RADIUS - UNIT, abs=0.02)
    assert abs(picked[0].position[0]) < 0.01 and abs(picked[0].position[1]) < 0.01
