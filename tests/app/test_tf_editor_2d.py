"""The 2D TF editor driven by real mouse and key events: widgets added, moved, resized, recoloured,
given an opacity and deleted; the editor following the model; undo; the 1D -> 2D switch."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from PyQt5.QtCore import QPoint, Qt
from PyQt5.QtGui import QColor

from tests.app.widget_input import shown
from volren.app.core import tf_widget_geometry as geometry
from volren.app.core.joint_histogram import joint_histogram, suggested_gradient_max
from volren.app.core.state import Change, ViewState, default_camera
from volren.app.tf_editor.two_d.editor import DEFAULT_OPACITY, TransferFunction2DEditor
from volren.model.colormaps import VIRIDIS, color_stops
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TFWidget, TransferFunction2D
from volren.model.volume import UniformVolume

VALUE_RANGE = (0.0, 1.8)
GMAX = 2.0


def sphere(n: int = 17) -> UniformVolume:
    axis = np.linspace(-1.0, 1.0, n)
    z, y, x = np.meshgrid(axis, axis, axis, indexing="ij")
    return UniformVolume(np.sqrt(x * x + y * y + z * z), (2.0 / (n - 1),) * 3, (-1.0,) * 3)


def tf_2d(*widgets: TFWidget) -> TransferFunction2D:
    return TransferFunction2D(VALUE_RANGE, (0.0, GMAX), widgets, 0.1)


GAUSSIAN = TFWidget.gaussian((0.9, 1.0), (0.1, 0.2), (1.0, 0.5, 0.0), 0.6)
BOX = TFWidget.box((0.3, 0.6), (0.2, 0.8), (0.0, 0.5, 1.0), 0.4)
TRIANGLE = TFWidget.triangle(1.3, 0.2, 1.5, (0.2, 1.0, 0.2), 0.7)


@pytest.fixture
def state() -> ViewState:
    s = ViewState()
    volume = sphere()
    s.load(volume, tf_2d(GAUSSIAN), default_camera(volume))
    return s


@pytest.fixture
def editor(qtbot, state) -> TransferFunction2DEditor:
    return shown(qtbot, TransferFunction2DEditor(state), (560, 440))


def drag(qtbot, widget, start: QPoint, end: QPoint, steps: int = 4) -> None:
    """Press, move and release through the QWindow, as real input arrives (Qt 5's QWidget
    mouseMove only moves the cursor, which delivers nothing on the offscreen platform)."""
    window = widget.window().windowHandle()

    def at(p: QPoint) -> QPoint:
        return widget.mapTo(widget.window(), p)

    qtbot.mousePress(window, Qt.LeftButton, Qt.NoModifier, at(start))
    for k in range(1, steps + 1):
        qtbot.mouseMove(window, at(start + (end - start) * k / steps))
    qtbot.mouseRelease(window, Qt.LeftButton, Qt.NoModifier, at(end))


def click(qtbot, widget, pos: QPoint) -> None:
    qtbot.mouseClick(widget, Qt.LeftButton, Qt.NoModifier, pos)


# ---------------------------------------------------------------------------- showing
def test_shows_the_histogram_and_the_widgets(editor, state):
    canvas = editor.canvas
    assert canvas.transfer_function is state.transfer_function
    expected = joint_histogram(state.volume, gradient_max=GMAX, value_range=VALUE_RANGE)
    assert canvas.histogram is expected
    # a Gaussian's centre pixel maps back to its centre (to within a pixel)
    s, g = canvas.to_data(canvas.widget_pixel(0))
    ds, dg = np.subtract(canvas.to_data(QPoint(1, 0)), canvas.to_data(QPoint(0, 1)))
    assert s == pytest.approx(0.9, abs=abs(ds)) and g == pytest.approx(1.0, abs=abs(dg))
    assert canvas.widget_at(canvas.widget_pixel(0)) == 0
    assert canvas.widget_at(canvas.to_pixel(0.1, 1.9)) is None
    image = canvas.grab().toImage()
    p = canvas.widget_pixel(0)
    assert QColor(image.pixel(p)).red() > QColor(image.pixel(p)).blue()  # orange fill over grey


def test_a_click_selects_and_a_click_elsewhere_clears(qtbot, editor, state, history):
    canvas = editor.canvas
    click(qtbot, canvas, canvas.widget_pixel(0))
    assert editor.selected_index == 0
    assert editor.opacity_spin.value() == pytest.approx(0.6) and editor.opacity_spin.isEnabled()
    click(qtbot, canvas, canvas.to_pixel(0.1, 1.9).toPoint())
    assert editor.selected_index is None and not editor.opacity_spin.isEnabled()
    assert history.stack.count() == 0  # selecting changes nothing


# ---------------------------------------------------------------------------- adding
@pytest.mark.parametrize("kind", ["gaussian", "triangle", "box"])
def test_each_add_button_adds_its_widget_at_the_view_centre(qtbot, editor, state, kind):
    button = {
        "gaussian": editor.add_gaussian_button,
        "triangle": editor.add_triangle_button,
        "box": editor.add_box_button,
    }
    qtbot.mouseClick(button[kind], Qt.LeftButton)
    tf = state.transfer_function
    assert len(tf.widgets) == 2
    added = tf.widgets[1]
    assert added.type == kind and added.opacity == DEFAULT_OPACITY
    assert geometry.center(added)[0] == pytest.approx(0.9)  # the middle of the value axis
    assert 0.0 < geometry.center(added)[1] < GMAX
    assert editor.selected_index == 1


def test_place_widget_at_adds_a_selected_gaussian_there(editor, state):
    index = editor.place_widget_at(0.42, 1.25)
    tf = state.transfer_function
    assert index == 1 and editor.selected_index == 1
    widget = tf.widgets[1]
    assert widget.type == "gaussian" and widget.center == (0.42, 1.25)
    assert widget.width == pytest.approx((1.8 / 40, GMAX / 20))
    assert tf.sample(0.42, 1.25)[1] == pytest.approx(
        1 - (1 - widget.opacity) * (1 - GAUSSIAN.opacity_at(0.42, 1.25))
    )


def test_place_widget_at_with_a_1d_tf_reports_an_error(qtbot, editor, state):
    state.set_transfer_function(TransferFunction1D.ramp(0.0, 1.8))
    with qtbot.waitSignal(editor.errorOccurred, timeout=1000) as blocker:
        assert editor.place_widget_at(0.5, 0.5) is None
    assert blocker.args[0] == "Cannot place a widget"


# ---------------------------------------------------------------------------- dragging
def test_dragging_moves_the_centre_by_the_dragged_data_amount_in_one_undo_step(qtbot, editor, state, history):
    canvas = editor.canvas
    changes: list[Change] = []
    state.subscribe(changes.append)
    start = canvas.widget_pixel(0)
    end = start + QPoint(40, -30)
    expected = np.add(GAUSSIAN.center, np.subtract(canvas.to_data(end), canvas.to_data(start)))
    drag(qtbot, canvas, start, end)
    widget = state.transfer_function.widgets[0]
    np.testing.assert_allclose(widget.center, expected, rtol=1e-12)
    assert widget.center[0] > 0.9 and widget.center[1] > 1.0  # right and up
    assert widget.width == GAUSSIAN.width
    # previews while dragging, then the end of the interaction
    assert [c for c in changes if c.what == "tf"] and all(c.interactive for c in changes if c.what == "tf")
    assert changes[-1] == Change("interaction", False)
    assert history.stack.count() == 1
    history.undo()
    assert state.transfer_function.widgets[0].center == GAUSSIAN.center
    assert editor.canvas.transfer_function is state.transfer_function  # follows the replaced TF


def test_dragging_a_box_handle_resizes_it(qtbot, editor, state):
    tf = state.transfer_function
    tf.set_widgets([BOX])
    canvas = editor.canvas
    editor.select(0)
    start = canvas.handle_pixel(0, "top")
    end = start + QPoint(7, -25)  # sideways motion means nothing to an edge handle
    drag(qtbot, canvas, start, end)
    box = tf.widgets[0]
    assert box.gradient_range[1] == pytest.approx(canvas.to_data(end)[1], rel=1e-12)
    assert box.gradient_range[1] > 0.8
    assert box.gradient_range[0] == 0.2 and box.value_range == (0.3, 0.6)


def test_dragging_a_gaussian_corner_resizes_it_symmetrically(qtbot, editor, state):
    canvas = editor.canvas
    editor.select(0)
    start = canvas.handle_pixel(0, "top_right")
    end = start + QPoint(20, -12)
    drag(qtbot, canvas, start, end)
    widget = state.transfer_function.widgets[0]
    s, g = canvas.to_data(end)
    assert widget.width == pytest.approx(
        ((s - 0.9) / geometry.GAUSSIAN_EXTENT, (g - 1.0) / geometry.GAUSSIAN_EXTENT)
    )
    assert widget.center == GAUSSIAN.center


def test_dragging_a_triangle_corner_sets_half_width_and_height(qtbot, editor, state):
    tf = state.transfer_function
    tf.set_widgets([TRIANGLE])
    canvas = editor.canvas
    click(qtbot, canvas, canvas.widget_pixel(0))  # select by clicking inside
    assert editor.selected_index == 0
    start = canvas.handle_pixel(0, "top_left")
    end = start + QPoint(-15, 20)
    drag(qtbot, canvas, start, end)
    s, g = canvas.to_data(end)
    widget = tf.widgets[0]
    assert widget.half_width == pytest.approx(1.3 - s) and widget.gradient_max == pytest.approx(g)
    assert widget.value == 1.3


def test_resizing_stops_at_the_minimum_size(qtbot, editor, state):
    canvas = editor.canvas
    editor.select(0)
    start = canvas.handle_pixel(0, "right")
    drag(qtbot, canvas, start, canvas.widget_pixel(0))  # onto the centre: zero width
    assert state.transfer_function.widgets[0].width[0] == pytest.approx(canvas.minimum_size()[0])


# ---------------------------------------------------------------------------- properties
def test_colour_button_recolours_the_selected_widget(qtbot, editor, state, history):
    asked = []

    def choose(initial: QColor) -> QColor | None:
        asked.append(initial.getRgbF()[:3])
        return QColor(255, 0, 51)

    editor.choose_color = choose
    editor.select(0)
    qtbot.mouseClick(editor.color_button, Qt.LeftButton)
    assert asked == [pytest.approx(GAUSSIAN.color, abs=1 / 255)]
    assert state.transfer_function.widgets[0].color == pytest.approx((1.0, 0.0, 0.2))
    editor.choose_color = lambda initial: None  # cancelled: nothing changes
    qtbot.mouseClick(editor.color_button, Qt.LeftButton)
    assert state.transfer_function.widgets[0].color == pytest.approx((1.0, 0.0, 0.2))
    assert history.stack.count() == 1


def test_opacity_spin_box_sets_the_peak_opacity(editor, state):
    editor.select(0)
    editor.opacity_spin.setValue(0.25)
    assert state.transfer_function.widgets[0].opacity == 0.25
    assert state.transfer_function.sample(0.9, 1.0)[1] == pytest.approx(0.25)


def test_gradient_max_control_changes_the_axis_and_the_histogram(editor, state, history):
    editor.gradient_max_spin.setValue(3.5)
    tf = state.transfer_function
    assert tf.gradient_range == (0.0, 3.5)
    assert editor.canvas.histogram.gradient_max == 3.5
    editor.fit_gradient_button.click()
    assert tf.gradient_range[1] == pytest.approx(suggested_gradient_max(state.volume))
    assert editor.gradient_max_spin.value() == pytest.approx(tf.gradient_range[1], rel=1e-3)
    assert history.stack.count() == 2


def test_delete_key_and_button_remove_the_selected_widget(qtbot, editor, state):
    tf = state.transfer_function
    tf.set_widgets([GAUSSIAN, BOX, TRIANGLE])
    canvas = editor.canvas
    click(qtbot, canvas, canvas.widget_pixel(1))
    assert editor.selected_index == 1
    qtbot.keyClick(canvas, Qt.Key_Delete)
    assert tf.widgets == (GAUSSIAN, TRIANGLE) and editor.selected_index is None
    editor.select(1)
    qtbot.mouseClick(editor.delete_button, Qt.LeftButton)
    assert tf.widgets == (GAUSSIAN,)
    assert not editor.delete_button.isEnabled()


# ---------------------------------------------------------------------------- model -> editor
def test_edits_to_the_model_show_in_the_editor(editor, state):
    canvas = editor.canvas
    editor.select(0)
    before = canvas.widget_pixel(0)
    state.transfer_function.replace_widget(0, TFWidget.gaussian((0.45, 0.5), (0.1, 0.2), (0, 0, 1), 0.9))
    after = canvas.widget_pixel(0)
    assert after.x() < before.x() and after.y() > before.y()  # left and down
    assert editor.opacity_spin.value() == pytest.approx(0.9)
    assert state.transfer_function.widgets[0].opacity == 0.9  # syncing the spin box wrote nothing back
    replacement = tf_2d(BOX, TRIANGLE)
    state.set_transfer_function(replacement)
    assert canvas.transfer_function is replacement
    assert editor.selected_index == 0  # still a valid index
    state.set_transfer_function(tf_2d())
    assert editor.selected_index is None


def test_a_new_volume_recomputes_the_histogram(editor, state):
    first = editor.canvas.histogram
    volume = sphere(9)
    state.load(volume, tf_2d(GAUSSIAN), default_camera(volume))
    assert editor.canvas.histogram is not first
    assert editor.canvas.histogram is joint_histogram(volume, gradient_max=GMAX, value_range=VALUE_RANGE)


# ---------------------------------------------------------------------------- 1D -> 2D
VIRIDIS_RAMP = TransferFunction1D(color_stops(VIRIDIS, 0.2, 1.5), [[0.2, 0.0], [1.5, 0.8]], 0.3)


def use_2d(qtbot, editor, state, tf_1d: TransferFunction1D) -> TransferFunction2D:
    """Load `tf_1d` in a fresh scene (no 2D TF of this volume to return to) and click the button."""
    state.load(state.volume, tf_1d, state.camera)
    assert editor.use_2d_button.isVisibleTo(editor) and not editor.canvas.isVisibleTo(editor)
    assert editor.use_2d_button.isEnabled()
    qtbot.mouseClick(editor.use_2d_button, Qt.LeftButton)
    assert isinstance(state.transfer_function, TransferFunction2D)
    return state.transfer_function


def test_with_a_1d_tf_the_button_makes_a_2d_one_that_draws_the_same(qtbot, editor, state, history):
    tf = use_2d(qtbot, editor, state, VIRIDIS_RAMP)
    assert tf.value_range == state.volume.value_range
    gmax = suggested_gradient_max(state.volume)
    assert tf.gradient_range == (0.0, gmax)
    assert tf.opacity_unit_distance == 0.3
    # colour and opacity along value as the 1D TF's, at every gradient magnitude: not a flat box
    # of the ramp's middle colour and opacity
    table = tf.table(n_values=181, n_gradients=9)
    lut = VIRIDIS_RAMP.to_lut(181, tf.value_range)
    assert np.abs(table - lut[None]).max() <= 1e-6
    assert [w.type for w in tf.widgets] == ["1d"]
    lo, hi = tf.value_range
    assert geometry.outline(tf.widgets[0]) == [(lo, 0.0), (hi, 0.0), (hi, gmax), (lo, gmax)]  # a full band
    assert editor.canvas.isVisibleTo(editor) and editor.canvas.transfer_function is tf
    history.undo()
    assert state.transfer_function.dims == 1


def test_the_2d_tfs_band_drags_as_a_whole(qtbot, editor, state, history):
    tf = use_2d(qtbot, editor, state, VIRIDIS_RAMP)
    canvas = editor.canvas
    band = tf.widgets[0]
    start = canvas.to_pixel(0.9, 0.3 * tf.gradient_range[1]).toPoint()
    end = start + QPoint(-30, -20)
    ds, dg = np.subtract(canvas.to_data(end), canvas.to_data(start))
    drag(qtbot, canvas, start, end)
    moved = tf.widgets[0]
    assert moved.type == "1d" and ds < 0 < dg
    np.testing.assert_allclose(
        np.array(moved.color_points), np.array(band.color_points) + [ds, 0, 0, 0], rtol=1e-12
    )
    np.testing.assert_allclose(
        np.array(moved.opacity_points), np.array(band.opacity_points) + [ds, 0], rtol=1e-12
    )
    np.testing.assert_allclose(moved.gradient_range, np.add(band.gradient_range, dg), rtol=1e-12)
    assert history.stack.count() == 2  # the switch to 2D, then the drag
    editor.select(0)
    handle = canvas.handle_pixel(0, "right")
    drag(qtbot, canvas, handle, handle + QPoint(-40, 0))
    stretched = tf.widgets[0]
    s_lo, s_hi = stretched.opacity_points[0][0], stretched.opacity_points[-1][0]
    assert s_lo == pytest.approx(moved.opacity_points[0][0], rel=1e-12)
    assert s_hi == pytest.approx(canvas.to_data(handle + QPoint(-40, 0))[0], rel=1e-12)


def test_switching_to_2d_and_back_keeps_both_tfs(qtbot, editor, state):
    """Issue 23: 1D -> 2D -> 1D returns to the edited 1D TF, and 2D again to the edited 2D TF."""
    from volren.app.tf_editor.one_d.editor import TransferFunction1DEditor

    one_d = TransferFunction1DEditor(state)
    qtbot.addWidget(one_d)
    edited_1d = TransferFunction1D.ramp(0.2, 1.5, 0.7, (0.9, 0.3, 0.1))
    state.load(state.volume, edited_1d, state.camera)
    qtbot.mouseClick(editor.use_2d_button, Qt.LeftButton)
    edited_2d = state.transfer_function
    edited_2d.replace_widget(0, replace(edited_2d.widgets[0], opacity=0.123))
    one_d.use_1d_button.setVisible(True)
    qtbot.mouseClick(one_d.use_1d_button, Qt.LeftButton)
    assert state.transfer_function is edited_1d
    qtbot.mouseClick(editor.use_2d_button, Qt.LeftButton)
    assert state.transfer_function is edited_2d and edited_2d.widgets[0].opacity == 0.123


def test_no_2d_tf_is_offered_where_no_renderer_draws_one(qtbot, state):
    """Issue 23: on a kind of volume no renderer draws 2D TFs for (tetrahedral meshes), the button
    is disabled with the reason, instead of making a TF that fails to render."""
    reason = "No renderer draws 2D transfer functions on uniform volumes"
    editor = TransferFunction2DEditor(state, two_d_reason=lambda kind: reason if kind == "uniform" else None)
    qtbot.addWidget(editor)
    state.set_transfer_function(TransferFunction1D.ramp(0.0, 1.0))
    assert not editor.use_2d_button.isEnabled() and editor.use_2d_button.toolTip() == reason
    assert reason in editor.message_label.text()
    editor.use_2d_transfer_function()  # a scripted call is refused as well
    assert state.transfer_function.dims == 1


def test_the_button_is_disabled_without_a_volume(qtbot):
    editor = TransferFunction2DEditor(ViewState())
    qtbot.addWidget(editor)
    assert editor.use_2d_button.isVisibleTo(editor)
    assert not editor.use_2d_button.isEnabled()
    assert "Open a volume" in editor.message_label.text()


def test_a_detached_editor_no_longer_follows_the_state(editor, state):
    shown = editor.canvas.transfer_function
    editor.detach()
    editor.detach()  # twice is fine
    state.set_transfer_function(tf_2d(BOX))
    assert editor.canvas.transfer_function is shown


# ---------------------------------------------------------------------------- geometry rules
def test_nothing_moves_or_resizes_below_zero_gradient():
    moved = geometry.moved(GAUSSIAN, 0.1, -5.0)
    assert moved.center == pytest.approx((1.0, 0.0))
    box = geometry.moved(BOX, 0.0, -5.0)
    assert box.gradient_range == pytest.approx((0.0, 0.6))  # the whole box stops, keeping its height
    low = geometry.resized(BOX, "bottom_left", 0.1, -3.0, (0.01, 0.01))
    assert low.gradient_range == (0.0, 0.8) and low.value_range == (0.1, 0.6)
    squashed = geometry.resized(BOX, "top", 0.5, -1.0, (0.01, 0.05))
    assert squashed.gradient_range == pytest.approx((0.2, 0.25))
    triangle = geometry.moved(TRIANGLE, -0.3, 1.0)
    assert (triangle.value, triangle.gradient_max) == pytest.approx((1.0, 1.5))  # the apex stays on g = 0
    taller = geometry.resized(TRIANGLE, "top", 5.0, 1.9, (0.01, 0.01))
    assert (taller.half_width, taller.gradient_max) == (0.2, 1.9)


def test_hit_testing_follows_the_drawn_outlines():
    # triangle: apex (1.3, 0), top corners (1.1, 1.5) and (1.5, 1.5)
    assert geometry.contains(TRIANGLE, 1.3, 0.1) and geometry.contains(TRIANGLE, 1.45, 1.4)
    assert not geometry.contains(TRIANGLE, 1.45, 0.3) and not geometry.contains(TRIANGLE, 1.3, 1.6)
    # gaussian: the ellipse at two standard deviations
    assert geometry.contains(GAUSSIAN, 0.9 + 0.19, 1.0) and not geometry.contains(GAUSSIAN, 0.9 + 0.21, 1.0)
    assert geometry.contains(BOX, 0.3, 0.8) and not geometry.contains(BOX, 0.29, 0.5)
    for widget in (BOX, TRIANGLE):  # outlines are closed: their corners belong to them
        assert all(geometry.contains(widget, s, g) for s, g in geometry.outline(widget))
    radii = [((s - 0.9) / 0.2) ** 2 + ((g - 1.0) / 0.4) ** 2 for s, g in geometry.outline(GAUSSIAN)]
    np.testing.assert_allclose(radii, 1.0)


def test_a_1d_band_moves_and_resizes_like_a_box():
    band = TFWidget("1d", (1.0, 1.0, 1.0), 1.0, gradient_range=(0.5, 1.5),
                    color_points=[[0.2, 1, 0, 0], [1.0, 0, 0, 1]], opacity_points=[[0.4, 0], [0.6, 1]])  # fmt: skip
    assert geometry.contains(band, 0.2, 0.5) and geometry.contains(band, 1.0, 1.5)
    assert not geometry.contains(band, 0.19, 1.0) and not geometry.contains(band, 0.5, 0.49)
    moved = geometry.moved(band, 0.1, -5.0)  # the band stops at g = 0, keeping its height
    assert moved.gradient_range == (0.0, 1.0)
    np.testing.assert_allclose(moved.color_points, [[0.3, 1, 0, 0], [1.1, 0, 0, 1]], rtol=1e-15)
    np.testing.assert_allclose(moved.opacity_points, [[0.5, 0], [0.7, 1]], rtol=1e-15)
    # the left edge from 0.2 to 0.6: the points' span [0.2, 1] becomes [0.6, 1], linearly
    narrowed = geometry.resized(band, "left", 0.6, 3.0, (0.01, 0.01))
    np.testing.assert_allclose(narrowed.opacity_points, [[0.7, 0], [0.8, 1]], rtol=1e-15)
    assert narrowed.gradient_range == (0.5, 1.5) and narrowed.color_points[0][0] == 0.6
    lowered = geometry.resized(band, "bottom", 0.0, -1.0, (0.01, 0.01))
    assert lowered.gradient_range == (0.0, 1.5) and lowered.opacity_points == band.opacity_points
