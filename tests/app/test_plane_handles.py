"""A clip plane edited in the viewport: the Qt-free geometry of `core.plane_handles` against
closed forms, then the real window: View > Edit clip plane, a drag of the centre handle moving the
plane along its normal by the distance under the mouse (one interaction), and a Shift drag of
the tip snapping the normal to an axis."""

from __future__ import annotations

from typing import ClassVar

import numpy as np
import pytest
from PyQt5.QtCore import QPoint

from tests.app.conftest import FRAME_TIMEOUT_MS, FakeRenderer
from tests.app.test_crop_handles import drag, to_point, window_events
from tests.app.viewport_pixels import frame_rect
from volren.app.core.overlay_geometry import project_points
from volren.app.core.plane_handles import ARROW_SHARE, PlaneDrag, handle_points, plane_polygon, snapped
from volren.model.camera import Camera
from volren.model.clip_region import ClipPlane
from volren.renderers.base import Capabilities, KindSupport
from volren.renderers.registry import registry

BOUNDS = (0.0, 1.0, 0.0, 1.0, 0.0, 1.0)


def test_a_plane_across_a_cube_is_a_square_and_an_oblique_one_a_hexagon():
    square = plane_polygon(ClipPlane((0.25, 0.5, 0.5), (1.0, 0.0, 0.0)), BOUNDS)
    assert len(square) == 4 and np.allclose(square[:, 0], 0.25)
    assert sorted(map(tuple, np.round(square[:, 1:], 9))) == [(0, 0), (0, 1), (1, 0), (1, 1)]
    hexagon = plane_polygon(ClipPlane((0.5, 0.5, 0.5), (1.0, 1.0, 1.0)), BOUNDS)
    assert len(hexagon) == 6 and np.allclose(hexagon.sum(axis=1), 1.5)
    # in order around the polygon: every side is an edge of the hexagon (length sqrt(2) / 2)
    sides = np.linalg.norm(np.roll(hexagon, -1, axis=0) - hexagon, axis=1)
    assert np.allclose(sides, 2**0.5 / 2)
    assert plane_polygon(ClipPlane((5.0, 0.0, 0.0), (1.0, 0.0, 0.0)), BOUNDS).shape == (0, 3)


def test_the_turn_handle_points_to_the_kept_side():
    centre, tip = handle_points(ClipPlane((0.3, 0.2, 0.9), (0.0, 0.0, 2.0)), BOUNDS)
    assert np.allclose(centre, (0.5, 0.5, 0.9))
    assert np.allclose(tip - centre, (0.0, 0.0, ARROW_SHARE * 3**0.5))
    _, tip = handle_points(ClipPlane((0.3, 0.2, 0.9), (0.0, 0.0, 2.0), invert=True), BOUNDS)
    assert tip[2] < centre[2]


@pytest.mark.parametrize("parallel", [False, True])
def test_a_move_follows_the_mouse_along_the_normal_and_stops_at_the_box(parallel):
    camera = Camera.orbit(BOUNDS, 0.0, 0.0, parallel=parallel)  # looking down -z: +x is right on screen
    rect = (0.0, 0.0, 400.0, 400.0)
    plane = ClipPlane((0.5, 0.5, 0.5), (1.0, 0.0, 0.0))
    drag_ = PlaneDrag.start_at("move", camera, 1.0, rect, plane, BOUNDS)
    assert drag_ is not None and drag_.normal_pixels[0] > 0 and abs(drag_.normal_pixels[1]) < 1e-6
    # oracle: 0.2 world units at the handle's depth are this many pixels
    centre = np.array([0.5, 0.5, 0.5])
    pixels = project_points(camera, 1.0, rect, np.stack([centre, centre + (0.2, 0, 0)]))
    dx = pixels[1, 0] - pixels[0, 0]
    assert drag_.plane_for(dx, 37.0).origin == pytest.approx((0.7, 0.5, 0.5))  # vertical motion: no effect
    assert drag_.plane_for(1e6, 0.0).origin[0] == pytest.approx(1.0)
    assert drag_.plane_for(-1e6, 0.0).origin[0] == pytest.approx(0.0)
    # a normal along the view has no direction on screen to follow: not offered
    assert (
        PlaneDrag.start_at("move", camera, 1.0, rect, ClipPlane((0.5, 0.5, 0.5), (0, 0, 1)), BOUNDS) is None
    )


def test_a_turn_rotates_the_normal_about_the_cameras_up_axis_and_shift_snaps_it():
    camera = Camera.orbit(BOUNDS, 0.0, 0.0)
    rect = (0.0, 0.0, 400.0, 400.0)
    plane = ClipPlane((0.5, 0.5, 0.5), (1.0, 0.0, 0.0))
    drag_ = PlaneDrag.start_at("turn", camera, 1.0, rect, plane, BOUNDS)
    assert drag_ is not None
    quarter = drag_.plane_for(200.0, 0.0)  # half the view's side: a quarter turn about +y
    assert np.allclose(quarter.normal, (0.0, 0.0, -1.0), atol=1e-9) or np.allclose(
        quarter.normal, (0, 0, 1), atol=1e-9
    )
    assert np.allclose(quarter.origin, (0.5, 0.5, 0.5))
    tilted = drag_.plane_for(60.0, 0.0, snap=True)
    assert tilted.normal == (1.0, 0.0, 0.0)
    assert snapped((-0.2, -0.9, 0.3)) == (0.0, -1.0, 0.0)


class ClippingFake(FakeRenderer):
    name: ClassVar[str] = "fake_clipping"
    capabilities: ClassVar[Capabilities] = Capabilities(kinds={"uniform": KindSupport(clip_region=True)},
                                                        summary="clips")  # fmt: skip


@pytest.fixture
def shown(make_window, fake_renderers, sample, qtbot):
    registry.register(ClippingFake.name, ClippingFake, replace=True)
    window = make_window()
    with qtbot.waitSignal(window.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        window.files.apply_loaded(sample, ClippingFake.name)
    with qtbot.waitSignal(window.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        window.view_direction_actions["+Z"].trigger()
    yield window
    registry.unregister(ClippingFake.name)


@pytest.mark.qt
def test_dragging_the_centre_handle_moves_the_plane_under_the_mouse_in_one_interaction(shown, qtbot):
    w = shown
    state = w.state
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.docks.clipping.add_plane()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.docks.clipping.axis_buttons["X"].click()
    assert w.viewport.clip_plane is None
    w.clip_handles_action.trigger()
    assert w.viewport.clip_plane == 0
    frame = w.viewport.frame
    rect = frame_rect(w.viewport)
    camera, aspect = frame.camera, frame.width / frame.height
    plane = state.settings.clip.planes[0]
    centre = handle_points(plane, state.volume.bounds)[0]
    start = to_point(project_points(camera, aspect, rect, centre[None])[0])
    target = centre + (0.4, 0.0, 0.0)
    dx = float(
        project_points(camera, aspect, rect, target[None])[0, 0]
        - project_points(camera, aspect, rect, centre[None])[0, 0]
    )
    before = state.camera
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS) as shown_frame:
        drag(qtbot, w.viewport, start, start + QPoint(round(dx), 0))
    moved = state.settings.clip.planes[0]
    assert abs(dx) > 20  # the motion is many pixels: rounding to whole pixels moves it by 2 at most
    assert moved.origin[0] == pytest.approx(centre[0] + 0.4, abs=2.0 * 0.4 / abs(dx))
    assert moved.normal == plane.normal and state.camera == before  # the camera did not turn
    assert shown_frame.args[0].settings.clip.planes == state.settings.clip.planes


@pytest.mark.qt
def test_a_shift_drag_of_the_tip_snaps_the_normal_to_an_axis(shown, qtbot):
    from PyQt5.QtCore import Qt

    w = shown
    state = w.state
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.docks.clipping.add_plane()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.docks.clipping.set_normal((1.0, 0.3, 0.0))
    w.clip_handles_action.trigger()
    frame = w.viewport.frame
    rect = frame_rect(w.viewport)
    tip = handle_points(state.settings.clip.planes[0], state.volume.bounds)[1]
    start = to_point(project_points(frame.camera, frame.width / frame.height, rect, tip[None])[0])
    press, move, release = window_events(qtbot, w.viewport)
    handle = w.viewport.window().windowHandle()
    press(start)
    qtbot.mouseMove(handle, w.viewport.mapTo(w.viewport.window(), start + QPoint(8, 3)))
    at = w.viewport.mapTo(w.viewport.window(), start + QPoint(10, 4))
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        qtbot.mouseMove(handle, at)
        w.viewport.mouseMoveEvent(_shift_move(w.viewport, start + QPoint(12, 4)))
        qtbot.mouseRelease(handle, Qt.LeftButton, pos=at)
    assert state.settings.clip.planes[0].normal == (1.0, 0.0, 0.0)


def _shift_move(viewport, pos: QPoint):
    from PyQt5.QtCore import QPointF, Qt
    from PyQt5.QtGui import QMouseEvent

    return QMouseEvent(QMouseEvent.MouseMove, QPointF(pos), Qt.NoButton, Qt.LeftButton, Qt.ShiftModifier)
