"""The docks in the window: editors and panels drive the frames, undo from the Edit menu,
Ctrl+click on the volume places a 2D widget, panels follow the renderer's capabilities."""

from __future__ import annotations

import numpy as np
import pytest
from PyQt5.QtCore import QPoint, Qt

from tests.app.conftest import FRAME_TIMEOUT_MS

pytestmark = pytest.mark.qt


def frame_after(qtbot, window, act) -> object:
    """Run `act` and return the full-quality frame that follows it."""
    with qtbot.waitSignal(window.fullFrameShown, timeout=FRAME_TIMEOUT_MS) as blocker:
        act()
    return blocker.args[0]


def test_the_window_has_the_editors_and_panels_docked(loaded_window):
    w = loaded_window
    docks = w.docks
    assert docks.tf_dock.widget().widget() is docks.tf_panel and not docks.tf_dock.isHidden()  # in a scroll area
    assert docks.tf_panel.tabs.currentWidget() is docks.tf_panel.editor_1d
    assert docks.dataset.facts()["Dimensions"] == " × ".join(str(n) for n in w.state.volume.dimensions)
    width, height = w.viewport.pixel_size()
    assert width >= 400 and height >= 400, "the docks squeeze the viewport"


@pytest.mark.parametrize("size", [(1300, 760), (900, 600), (640, 480)])
def test_the_viewport_keeps_half_the_window_as_it_shrinks(loaded_window, qtbot, size):
    """Issue 23: the docks kept their width (at 900x600 the viewport was 169 px wide); they give
    way down to a minimum, their controls scrolling, and stay visible."""
    w = loaded_window
    w.resize(*size)
    qtbot.waitUntil(lambda: w.width() == size[0], timeout=2000)
    qtbot.wait(50)
    assert w.viewport.width() >= 0.47 * w.width(), (w.viewport.width(), w.width())
    for dock in (w.docks.tf_dock, w.docks.settings_dock):
        assert dock.isVisible() and dock.width() >= 150


def test_a_click_in_the_1d_editor_renders_a_new_frame_and_undo_restores_it(loaded_window, qtbot):
    w = loaded_window
    curve = w.docks.tf_panel.editor_1d.curve
    before = w.viewport.frame.rgb.copy()
    points = w.state.transfer_function.opacity_points.copy()
    lo, hi = w.state.volume.value_range
    at = curve.position_of(lo + 0.6 * (hi - lo), 1.0)  # an opaque point in the middle of the data
    frame = frame_after(qtbot, w, lambda: qtbot.mouseClick(curve, Qt.LeftButton, pos=QPoint(at)))
    assert len(w.state.transfer_function.opacity_points) == len(points) + 1
    assert np.abs(frame.rgb.astype(int) - before).max() > 20, "the edit did not change the frame"
    assert w.docks.undo_action.isEnabled()
    frame = frame_after(qtbot, w, w.docks.undo_action.trigger)
    np.testing.assert_array_equal(w.state.transfer_function.opacity_points, points)
    assert np.abs(frame.rgb.astype(int) - before).max() <= 1


def test_a_lighting_edit_reaches_the_renderer(loaded_window, qtbot):
    w = loaded_window
    assert not w.state.settings.shade
    frame = frame_after(qtbot, w, lambda: w.docks.lighting.shade.click())
    assert w.state.settings.shade and frame.full


def test_ctrl_click_on_the_volume_places_a_2d_widget(loaded_window, qtbot):
    w = loaded_window
    editor = w.docks.tf_panel.editor_2d
    frame_after(qtbot, w, editor.use_2d_button.click)
    assert w.state.transfer_function.dims == 2 and w.docks.tf_panel.tabs.currentWidget() is editor
    from volren.app.core.picking import pick

    tf = w.state.transfer_function
    widgets = len(tf.widgets)
    width, height = w.viewport.pixel_size()
    hit = pick(w.state.volume, tf, w.state.camera, width // 2, height // 2, width, height)
    assert hit is not None
    w.docks.pick(width // 2, height // 2)  # what the viewport's Ctrl+click emits
    assert len(tf.widgets) == widgets + 1
    assert tf.widgets[-1].center == pytest.approx((hit.value, hit.gradient_magnitude))


def test_ctrl_click_with_a_1d_tf_only_explains(loaded_window):
    w = loaded_window
    width, height = w.viewport.pixel_size()
    before = w.state.transfer_function.to_dict()
    w.docks.pick(width // 2, height // 2)
    assert w.state.transfer_function.to_dict() == before and "2D" in w.statusBar().currentMessage()


def test_panels_follow_the_renderer_capabilities(loaded_window, qtbot):
    w = loaded_window
    assert w.docks.current_support() == w.registry.capabilities("vtk").kinds["uniform"]
    vtk_pre = w.registry.capabilities("vtk").kinds["uniform"].preintegration
    assert w.docks.sampling.preintegration.isEnabled() == vtk_pre
    frame_after(qtbot, w, lambda: w.renderers.switch("slicer"))
    assert w.docks.sampling.preintegration.isEnabled()  # the slicer pre-integrates


def test_a_crop_error_is_reported_in_one_line(loaded_window, error_boxes):
    w = loaded_window
    w.docks.crop.errorOccurred.emit("Cannot crop", "crop box: xmin 2 is above xmax 1")
    assert error_boxes == [("Cannot crop", "crop box: xmin 2 is above xmax 1")]
