"""The crop box dragged by its faces in the viewport (issue 23): the Qt-free geometry of
`core.crop_handles` against oracles computed here from the camera's matrices and rays, then the
real window: the View menu's toggle, the handles painted over the frame, hovering, and drags that
crop (one interaction) or rotate the camera."""

from __future__ import annotations

from itertools import combinations

import numpy as np
import pytest
from PyQt5.QtCore import QPoint, Qt

from tests.app.viewport_pixels import frame_rect, grab
from volren.app.core.crop_handles import (
    FACE_NAMES,
    MESH_MIN_THICKNESS_SHARE,
    PICK_RADIUS,
    FaceDrag,
    cursor_kind,
    face_centres,
    handle_at,
    minimum_thickness,
    moved_face,
    seen_end_on,
    shown_box,
)
from volren.app.core.state import Change
from volren.app.core.view_directions import look_along, view_direction
from volren.app.rendering.overlays import AXIS_COLORS, CROP_BOX_COLOR, HANDLE_RADIUS, handle_color
from volren.model.camera import Camera, bounds_corners
from volren.model.volume import TetVolume, UniformVolume

FRAME_TIMEOUT_MS = 20000
#: An off-centre volume with three different extents, and a crop box inside it.
BOUNDS = (-1.0, 3.0, 0.5, 2.5, 4.0, 5.0)
CROP = (0.0, 2.0, 1.0, 2.0, 4.2, 4.8)
THICKNESS = (0.1, 0.1, 0.1)
#: The face centres of CROP, written out: xmin, xmax, ymin, ymax, zmin, zmax.
CROP_CENTRES = [
    (0.0, 1.5, 4.5),
    (2.0, 1.5, 4.5),
    (1.0, 1.0, 4.5),
    (1.0, 2.0, 4.5),
    (1.0, 1.5, 4.2),
    (1.0, 1.5, 4.8),
]


def project(camera: Camera, aspect: float, rect, points) -> np.ndarray:
    """World points to widget pixels, straight from the camera's matrices (x right, y down)."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    clip = np.c_[p, np.ones(len(p))] @ (camera.projection_matrix(aspect) @ camera.view_matrix()).T
    ndc = clip[:, :2] / clip[:, 3:]
    x, y, w, h = rect
    return np.c_[x + (ndc[:, 0] + 1) / 2 * w, y + (1 - ndc[:, 1]) / 2 * h]


def on_plane(camera: Camera, width: int, height: int, pixel, axis: int, level: float) -> np.ndarray:
    """Where the ray through the widget point `pixel` (of a frame drawn at (0, 0, width, height))
    meets the plane where coordinate `axis` equals `level`."""
    origin, direction = camera.rays(width, height, pixel[0] - 0.5, pixel[1] - 0.5)
    t = (level - origin[axis]) / direction[axis]
    return origin + t * direction


# ---------------------------------------------------------------------------------- geometry
def test_the_shown_box_is_the_crop_cut_to_the_bounds_or_the_whole_bounds():
    assert shown_box(None, BOUNDS) == BOUNDS
    assert shown_box(CROP, BOUNDS) == CROP
    assert shown_box((-5.0, 2.0, 1.0, 2.0, 4.2, 9.0), BOUNDS) == (-1.0, 2.0, 1.0, 2.0, 4.2, 5.0)


def test_face_centres_are_the_middles_of_the_six_faces_in_box_order():
    assert FACE_NAMES == ("-X", "+X", "-Y", "+Y", "-Z", "+Z")
    assert face_centres(CROP).tolist() == [list(c) for c in CROP_CENTRES]


@pytest.mark.parametrize("parallel", [False, True])
def test_the_handle_under_a_pixel_is_the_one_projected_there(parallel):
    cam = Camera.orbit(BOUNDS, 30.0, 20.0, 1.2, parallel=parallel).roll(12.0)
    rect = (10.0, 20.0, 400.0, 300.0)
    aspect = 400.0 / 300.0
    pixels = project(cam, aspect, rect, CROP_CENTRES)
    spread = min(np.linalg.norm(a - b) for a, b in combinations(pixels, 2))
    assert spread > 2 * PICK_RADIUS + 2, "precondition: the handles lie apart on screen"
    assert not any(seen_end_on(cam, CROP, face) for face in range(6))
    for face, (x, y) in enumerate(pixels):
        assert handle_at(cam, aspect, rect, CROP, x, y) == face
        for angle in np.linspace(0.0, 2 * np.pi, 8, endpoint=False):
            dx, dy = np.cos(angle), np.sin(angle)
            inside = handle_at(
                cam, aspect, rect, CROP, x + (PICK_RADIUS - 0.5) * dx, y + (PICK_RADIUS - 0.5) * dy
            )
            outside = handle_at(
                cam, aspect, rect, CROP, x + (PICK_RADIUS + 0.5) * dx, y + (PICK_RADIUS + 0.5) * dy
            )
            assert (inside, outside) == (face, None), f"face {FACE_NAMES[face]} at angle {angle:.2f}"


def test_faces_seen_end_on_are_not_offered():
    """Looking along +X at the box's centre the X faces' handles lie on the view axis: dragging
    them could not move them, so a press there is no handle (and rotates)."""
    cam = look_along(Camera.orbit(BOUNDS), view_direction("+X"), CROP)
    rect = (0.0, 0.0, 640.0, 480.0)
    pixels = project(cam, 640.0 / 480.0, rect, CROP_CENTRES)
    assert np.allclose(pixels[0], (320.0, 240.0)) and np.allclose(pixels[1], (320.0, 240.0))
    assert seen_end_on(cam, CROP, 0) and seen_end_on(cam, CROP, 1)
    assert handle_at(cam, 640.0 / 480.0, rect, CROP, 320.0, 240.0) is None
    assert FaceDrag.start(cam, 640.0 / 480.0, rect, CROP, 1, BOUNDS, THICKNESS) is None
    for face in range(2, 6):
        assert handle_at(cam, 640.0 / 480.0, rect, CROP, *pixels[face]) == face


@pytest.mark.parametrize("parallel", [False, True])
def test_after_a_plus_x_view_a_horizontal_drag_moves_the_y_face_by_the_distance_under_the_mouse(parallel):
    """Oracle: the rays through the handle's pixel and through the pixel the mouse moved to meet
    the face's plane (x = its centre's x) this far apart along y."""
    width, height = 640, 480
    rect = (0.0, 0.0, float(width), float(height))
    cam = look_along(Camera.orbit(BOUNDS, parallel=parallel), view_direction("+X"), BOUNDS)
    handle = project(cam, width / height, rect, CROP_CENTRES)[3]
    drag = FaceDrag.start(cam, width / height, rect, CROP, 3, BOUNDS, THICKNESS)
    assert drag is not None and drag.face == 3
    assert drag.cursor_kind() == "horizontal"
    dx = -30.0  # to the left: looking along +X with Z up, +Y points left
    start = on_plane(cam, width, height, handle, 0, CROP_CENTRES[3][0])
    end = on_plane(cam, width, height, handle + (dx, 0.0), 0, CROP_CENTRES[3][0])
    expected = end[1] - start[1]
    assert 0.2 < expected < 0.5, "precondition: a move the bounds leave room for"
    assert drag.distance(dx, 0.0) == pytest.approx(expected, rel=1e-9)
    box = drag.box_for(dx, 0.0)
    assert box[3] == pytest.approx(CROP[3] + expected, rel=1e-9)
    assert box[:3] + box[4:] == CROP[:3] + CROP[4:], "only the dragged face moves"
    assert drag.box_for(dx, 25.0) == box, "the motion across the face's axis counts for nothing"
    assert drag.box_for(0.0, -40.0) == CROP


def test_a_drag_stops_at_the_bounds_and_at_the_minimum_thickness():
    cam = look_along(Camera.orbit(BOUNDS), view_direction("+X"), BOUNDS)
    rect = (0.0, 0.0, 640.0, 480.0)
    ymax = FaceDrag.start(cam, 640.0 / 480.0, rect, CROP, 3, BOUNDS, THICKNESS)
    ymin = FaceDrag.start(cam, 640.0 / 480.0, rect, CROP, 2, BOUNDS, THICKNESS)
    assert ymax is not None and ymin is not None
    # +Y is on the left, -Y on the right: outward is left for ymax, right for ymin.
    assert ymax.box_for(-5000.0, 0.0) == CROP[:3] + (BOUNDS[3],) + CROP[4:]
    assert ymax.box_for(5000.0, 0.0) == CROP[:3] + (CROP[2] + THICKNESS[1],) + CROP[4:]
    assert ymin.box_for(5000.0, 0.0) == CROP[:2] + (BOUNDS[2],) + CROP[3:]
    assert ymin.box_for(-5000.0, 0.0) == CROP[:2] + (CROP[3] - THICKNESS[1],) + CROP[3:]
    # Measured from the press: past the bound and back, the face is under the mouse again.
    assert ymax.box_for(-5000.0, 0.0) != ymax.box_for(-10.0, 0.0) == ymax.box_for(-10.0, 3.0)


def test_moving_a_face_keeps_the_limits_and_never_thickens_a_thin_box():
    thin = (0.0, 2.0, 1.0, 1.05, 4.2, 4.8)  # thinner along y than the minimum (typed in the panel)
    assert moved_face(thin, 3, 0.9, BOUNDS, THICKNESS) == thin, "not pushed out to the thickness"
    assert moved_face(thin, 3, 1.3, BOUNDS, THICKNESS) == (0.0, 2.0, 1.0, 1.3, 4.2, 4.8)
    assert moved_face(thin, 2, 1.2, BOUNDS, THICKNESS) == thin
    assert moved_face(CROP, 0, -7.0, BOUNDS, THICKNESS) == (-1.0,) + CROP[1:]
    assert moved_face(CROP, 5, 4.5, BOUNDS, THICKNESS) == CROP[:5] + (4.5,)
    assert moved_face(CROP, 4, 4.75, BOUNDS, THICKNESS) == CROP[:4] + (4.8 - 0.1, 4.8)


def test_minimum_thickness_is_a_voxel_on_a_grid_and_a_share_of_the_extent_on_a_mesh():
    grid = UniformVolume(np.zeros((3, 5, 4), np.float32), spacing=(0.1, 0.2, 0.05))
    assert minimum_thickness(grid) == (0.1, 0.2, 0.05)
    points = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 4.0, 0.0], [0.0, 0.0, 1.0]]
    mesh = TetVolume(np.array(points), np.array([[0, 1, 2, 3]]), np.zeros(4))
    share = MESH_MIN_THICKNESS_SHARE
    assert minimum_thickness(mesh) == pytest.approx((2.0 * share, 4.0 * share, 1.0 * share), rel=1e-12)


@pytest.mark.parametrize(("vector", "kind"), [((1, 0), "horizontal"), ((-3, 0.5), "horizontal"), ((0, 1), "vertical"),
                                              ((0.2, -2), "vertical"), ((1, -1), "rising"), ((-1, 1), "rising"),
                                              ((1, 1), "falling"), ((-2, -2.3), "falling")])  # fmt: skip
def test_the_size_cursor_points_along_the_faces_axis_on_screen(vector, kind):
    assert cursor_kind(vector) == kind


# ------------------------------------------------------------------------------------- widgets


def handle_points(window, box) -> np.ndarray:
    """The widget pixels of `box`'s face centres with the camera of the frame on screen."""
    frame = window.viewport.frame
    centres = [[(box[0] + box[1]) / 2, (box[2] + box[3]) / 2, (box[4] + box[5]) / 2] for _ in range(6)]
    for face in range(6):
        centres[face][face // 2] = box[face]
    return project(frame.camera, frame.width / frame.height, frame_rect(window.viewport), centres)


def colour_at(pixels: np.ndarray, point) -> np.ndarray:
    x, y = (int(np.floor(v)) for v in point)
    return pixels[y, x].astype(int)


def rgb(color) -> np.ndarray:
    return np.array(color.getRgb()[:3])


def window_events(qtbot, viewport):
    """Mouse input through the viewport's QWindow (Qt 5's QWidget mouseMove delivers nothing
    offscreen): press, move (with the button state a real drag has) and release."""
    handle = viewport.window().windowHandle()

    def at(p: QPoint) -> QPoint:
        return viewport.mapTo(viewport.window(), p)

    return (lambda p: qtbot.mousePress(handle, Qt.LeftButton, pos=at(p)),
            lambda p: qtbot.mouseMove(handle, at(p)),
            lambda p: qtbot.mouseRelease(handle, Qt.LeftButton, pos=at(p)))  # fmt: skip


def drag(qtbot, viewport, start: QPoint, end: QPoint, steps: int = 4) -> None:
    press, move, release = window_events(qtbot, viewport)
    press(start)
    for k in range(1, steps + 1):
        move(start + (end - start) * (k / steps))
    release(end)


def to_point(pixel) -> QPoint:
    return QPoint(int(np.floor(pixel[0])), int(np.floor(pixel[1])))


@pytest.fixture
def shown(make_window, fake_renderers, sample, qtbot):
    """The window showing the Marschner-Lobb sample (-1..1 on each axis, spacing 0.05) with the
    constant-colour renderer, a full frame on screen."""
    window = make_window()
    with qtbot.waitSignal(window.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        window.files.apply_loaded(sample, "fake")
    return window


def show_view(window, qtbot, name: str) -> None:
    with qtbot.waitSignal(window.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        window.view_direction_actions[name].trigger()


@pytest.mark.qt
def test_the_view_menus_toggle_paints_the_box_and_its_handles_and_hides_them(shown, qtbot):
    w = shown
    action = w.crop_handles_action
    assert action in w.view_menu.actions() and action.isCheckable() and not action.isChecked()
    assert action.text() == "Edit crop box" and not w.viewport.crop_handles
    before = grab(w.viewport)
    box = (-0.6, 0.8, -0.9, 0.4, -0.5, 0.7)
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.state.set_crop(box)
    off = grab(w.viewport)
    action.trigger()
    assert w.viewport.crop_handles
    pixels = grab(w.viewport)
    points = handle_points(w, box)
    assert min(np.linalg.norm(a - b) for a, b in combinations(points, 2)) > 2 * HANDLE_RADIUS + 2
    for face, point in enumerate(points):
        assert np.array_equal(colour_at(pixels, point), rgb(AXIS_COLORS[face // 2])), FACE_NAMES[face]
        assert not np.array_equal(colour_at(off, point), rgb(AXIS_COLORS[face // 2]))
    frame = w.viewport.frame
    corners = project(frame.camera, frame.width / frame.height, frame_rect(w.viewport), bounds_corners(box))
    for i, j in ((0, 1), (0, 2), (0, 4), (7, 6), (7, 5), (7, 3)):
        mid = (corners[i] + corners[j]) / 2
        patch = (
            pixels[int(mid[1]) - 1 : int(mid[1]) + 2, int(mid[0]) - 1 : int(mid[0]) + 2]
            .reshape(-1, 3)
            .astype(int)
        )
        assert np.any(np.all(patch == rgb(CROP_BOX_COLOR), axis=1)), f"no crop box edge at {mid}"
    assert not np.array_equal(before, pixels)
    action.trigger()
    assert not w.viewport.crop_handles
    assert np.array_equal(grab(w.viewport), off), "off: nothing of the box or its handles is left"


@pytest.mark.qt
def test_with_no_crop_the_handles_sit_on_the_volumes_faces(shown, qtbot):
    w = shown
    w.crop_handles_action.trigger()
    pixels = grab(w.viewport)
    for face, point in enumerate(handle_points(w, w.state.volume.bounds)):
        assert np.array_equal(colour_at(pixels, point), rgb(AXIS_COLORS[face // 2])), FACE_NAMES[face]


@pytest.mark.qt
def test_dragging_a_face_handle_crops_by_the_distance_under_the_mouse_in_one_interaction(shown, qtbot):
    w = shown
    w.crop_handles_action.trigger()
    show_view(w, qtbot, "+X")
    camera, frame = w.state.camera, w.viewport.frame
    assert frame.camera == camera and frame_rect(w.viewport) == (0.0, 0.0, frame.width, frame.height)
    start = to_point(handle_points(w, w.state.volume.bounds)[3])  # +Y: on the left
    assert start.x() < w.viewport.width() / 2
    dx = 60
    # Oracle: where the rays through the pressed pixel and the released one meet the plane x = 0.
    a = on_plane(camera, frame.width, frame.height, (start.x() + 0.5, start.y() + 0.5), 0, 0.0)
    b = on_plane(camera, frame.width, frame.height, (start.x() + 0.5 + dx, start.y() + 0.5), 0, 0.0)
    expected = (-1.0, 1.0, -1.0, 1.0 + (b[1] - a[1]), -1.0, 1.0)
    assert 0.2 < 1.0 - expected[3] < 1.5, "precondition: a move well inside the volume"
    changes: list[Change] = []
    w.state.subscribe(changes.append)
    frames = []
    w.frameShown.connect(frames.append)
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        drag(qtbot, w.viewport, start, start + QPoint(dx, 0))
    assert w.state.crop == pytest.approx(expected, rel=1e-9, abs=1e-12)
    assert w.state.camera is camera, "a face drag does not turn the camera"
    crops = [c for c in changes if c.what == "crop"]
    assert len(crops) == 4 and all(c.interactive for c in crops), "each move a preview"
    assert [c for c in changes if c.what == "interaction"] == [Change("interaction", False)], (
        "one interaction"
    )
    assert changes[-1] == Change("interaction", False)
    assert any(not f.full for f in frames) and frames[-1].full
    assert w.docks.crop.enable.isChecked() and w.docks.crop.box() == w.state.crop, "the panel follows"
    assert not w.state.interacting


@pytest.mark.qt
def test_a_face_drag_stops_at_the_volumes_bounds_and_one_voxel_from_the_opposite_face(shown, qtbot):
    w = shown
    w.crop_handles_action.trigger()
    show_view(w, qtbot, "+X")
    bounds = w.state.volume.bounds
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        drag(qtbot, w.viewport, to_point(handle_points(w, bounds)[3]), to_point(handle_points(w, bounds)[3]) +
             QPoint(w.viewport.width(), 0))  # fmt: skip
    assert w.state.crop == pytest.approx((-1.0, 1.0, -1.0, -1.0 + 0.05, -1.0, 1.0), rel=1e-12)
    box = w.state.crop
    start = to_point(handle_points(w, box)[3])
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        drag(qtbot, w.viewport, start, QPoint(2, start.y()))
    assert w.state.crop is None, "back at the bound: the box covers the volume, nothing is cropped"


@pytest.mark.qt
def test_a_press_off_the_handles_rotates_and_the_toggle_turns_face_dragging_off(shown, qtbot):
    w = shown
    w.crop_handles_action.trigger()
    show_view(w, qtbot, "+X")
    points = handle_points(w, w.state.volume.bounds)
    away = QPoint(w.viewport.width() // 2 + 40, w.viewport.height() // 2 + 40)
    assert min(np.hypot(*(points - (away.x() + 0.5, away.y() + 0.5)).T)) > 3 * PICK_RADIUS
    camera = w.state.camera
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        drag(qtbot, w.viewport, away, away + QPoint(40, 0))
    assert w.state.crop is None and not np.allclose(w.state.camera.position, camera.position), "rotated"
    centre = QPoint(w.viewport.width() // 2, w.viewport.height() // 2)  # the X handles, seen end-on
    show_view(w, qtbot, "+X")
    camera = w.state.camera
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        drag(qtbot, w.viewport, centre, centre + QPoint(40, 0))
    assert w.state.crop is None and not np.allclose(w.state.camera.position, camera.position), (
        "end-on: rotated"
    )

    show_view(w, qtbot, "+X")
    w.crop_handles_action.trigger()
    assert not w.viewport.crop_handles
    camera = w.state.camera
    on_handle = to_point(handle_points(w, w.state.volume.bounds)[3])
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        drag(qtbot, w.viewport, on_handle, on_handle + QPoint(60, 0))
    assert w.state.crop is None, "handles off: no face drag"
    assert not np.allclose(w.state.camera.position, camera.position), "the press rotated instead"


@pytest.mark.qt
def test_hovering_a_handle_lights_it_and_shows_a_size_cursor_along_its_axis(shown, qtbot):
    w = shown
    vp = w.viewport
    w.crop_handles_action.trigger()
    show_view(w, qtbot, "+X")
    _press, move, _release = window_events(qtbot, vp)
    points = handle_points(w, w.state.volume.bounds)
    move(to_point(points[3]))
    assert vp.hot_face == 3 and vp.cursor().shape() == Qt.SizeHorCursor
    assert np.array_equal(colour_at(grab(vp), points[3]), rgb(handle_color(3, hot=True)))
    assert not np.array_equal(rgb(handle_color(3, hot=True)), rgb(AXIS_COLORS[1]))
    move(to_point(points[5]))  # +Z: above the centre, moves up and down
    assert vp.hot_face == 5 and vp.cursor().shape() == Qt.SizeVerCursor
    pixels = grab(vp)
    assert np.array_equal(colour_at(pixels, points[3]), rgb(AXIS_COLORS[1])), "no longer lit"
    assert np.array_equal(colour_at(pixels, points[5]), rgb(handle_color(5, hot=True)))
    move(QPoint(vp.width() // 2 + 40, vp.height() // 2 + 40))
    assert vp.hot_face is None and vp.cursor().shape() == Qt.ArrowCursor
    move(to_point(points[2]))
    w.crop_handles_action.trigger()
    assert vp.hot_face is None and vp.cursor().shape() == Qt.ArrowCursor, "off: nothing lit"
