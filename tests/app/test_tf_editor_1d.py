"""The 1D TF editor: gestures on the opacity curve and the colour bar change the state's TF by the
values under the mouse, a drag is one undo step, the panel follows TFs replaced in the state,
presets, range and unit boxes, files (volren JSON, ParaView presets, bad files) and 2D TFs.

Qt's test mouseMove does not deliver moves to a widget in the offscreen platform, so drags send
the QMouseEvents themselves (`widget_input.drag`); presses and releases go through qtbot.
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest
from PyQt5.QtCore import QPoint, Qt
from PyQt5.QtGui import QColor

from tests.app.widget_input import drag, shown
from volren.api import default_transfer_function
from volren.app.core.colormap_presets import (
    PRESET_NAMES,
    apply_preset,
    preset_color_points,
    unit_stops,
)
from volren.app.core.state import Change, ViewState, default_camera
from volren.app.tf_editor.history import TFHistory
from volren.app.tf_editor.one_d.editor import PRESET_PLACEHOLDER, TransferFunction1DEditor
from volren.app.tf_editor.one_d.opacity_curve import BOTTOM, TOP
from volren.app.tf_editor.one_d.point_canvas import MARGIN
from volren.errors import VolrenError
from volren.io import load_transfer_function
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TFWidget, TransferFunction2D
from volren.model.value_histogram import value_histogram
from volren.model.volume import UniformVolume
from volren.samples import marschner_lobb

SIZE = (320, 300)


# ---------------------------------------------------------------------------- fixtures and helpers
# `state` (the Marschner-Lobb sample: colour and opacity span [0, 1], the data range is inside it,
# so the value axis is [0, 1]) and `history` come from conftest
@pytest.fixture
def make_editor(qtbot):
    def make(state: ViewState) -> TransferFunction1DEditor:
        return shown(qtbot, TransferFunction1DEditor(state), SIZE)

    return make


@pytest.fixture
def editor(make_editor, state) -> TransferFunction1DEditor:
    return make_editor(state)


def value_per_pixel(editor: TransferFunction1DEditor) -> float:
    axis = editor.curve.axis
    return (axis.hi - axis.lo) / (editor.curve.width() - 2 * MARGIN)


def opacity_per_pixel(editor: TransferFunction1DEditor) -> float:
    return 1.0 / (editor.curve.height() - TOP - BOTTOM)


# ---------------------------------------------------------------------------- opacity curve
def test_the_value_axis_spans_tf_and_data_and_points_sit_where_drawn(editor, state):
    lo, hi = state.volume.value_range
    assert 0.0 < lo < hi == 1.0
    assert (editor.curve.axis.lo, editor.curve.axis.hi) == (0.0, 1.0)  # the TF starts below the data
    state.transfer_function.rescale(0.25, 0.5)
    assert (editor.curve.axis.lo, editor.curve.axis.hi) == (lo, hi)  # the data spans more now
    assert (editor.color_bar.axis.lo, editor.color_bar.axis.hi) == (lo, hi)
    state.transfer_function.rescale(0.0, 1.0)
    curve = editor.curve
    positions = editor.point_positions()
    assert len(positions) == 5
    # value 0 at the left margin, 1 at the right one; opacity 0 at the bottom, 0.7 two thirds up
    assert positions[0] == QPoint(MARGIN, curve.height() - BOTTOM)
    assert positions[-1] == QPoint(curve.width() - MARGIN, curve.height() - BOTTOM)
    assert positions[2].x() == pytest.approx((curve.width()) / 2, abs=1)
    assert positions[2].y() == pytest.approx(
        curve.height() - BOTTOM - 0.7 * (curve.height() - TOP - BOTTOM), abs=1
    )


def test_click_on_empty_space_adds_the_point_under_the_mouse(qtbot, editor, state, history):
    curve = editor.curve
    pos = curve.position_of(0.25, 0.5)
    qtbot.mouseClick(curve, Qt.LeftButton, pos=pos)
    points = state.transfer_function.opacity_points
    assert len(points) == 6
    x, a = points[1]
    assert x == pytest.approx(0.25, abs=value_per_pixel(editor))
    assert a == pytest.approx(0.5, abs=opacity_per_pixel(editor))
    assert curve.selected == 1
    assert history.stack.count() == 1
    history.undo()
    assert len(state.transfer_function.opacity_points) == 5


def test_drag_moves_a_point_and_is_one_undo_step(qtbot, editor, state, history):
    changes: list[Change] = []
    state.subscribe(changes.append)
    before = state.transfer_function.opacity_points
    start = editor.point_positions()[2]  # (0.5, 0.7)
    target = editor.curve.position_of(0.55, 0.3)
    drag(qtbot, editor.curve, start, target)

    after = state.transfer_function.opacity_points
    assert after[2, 0] == pytest.approx(0.55, abs=value_per_pixel(editor))
    assert after[2, 1] == pytest.approx(0.3, abs=opacity_per_pixel(editor))
    np.testing.assert_array_equal(np.delete(after, 2, axis=0), np.delete(before, 2, axis=0))
    assert editor.point_positions()[2] == target
    # previews while dragging, one full-quality announcement at the end, one undo step
    tf_changes = [c for c in changes if c.what == "tf"]
    assert len(tf_changes) == 4 and all(c.interactive for c in tf_changes)
    assert changes[-1] == Change("interaction", False) and not state.interacting
    assert history.stack.count() == 1

    history.undo()
    np.testing.assert_array_equal(state.transfer_function.opacity_points, before)
    assert editor.point_positions()[2] == start  # the editor follows the replaced TF
    history.redo()
    np.testing.assert_array_equal(state.transfer_function.opacity_points, after)


def test_a_dragged_point_stays_between_its_neighbours_and_in_0_1(qtbot, editor, state):
    curve = editor.curve
    start = editor.point_positions()[2]
    drag(qtbot, curve, start, QPoint(curve.width() - 2, -40))  # past the next point, above the top
    x, a = state.transfer_function.opacity_points[2]
    assert (x, a) == (0.6, 1.0)  # the neighbour's value, full opacity
    drag(qtbot, curve, editor.point_positions()[2], QPoint(0, curve.height() + 40))
    x, a = state.transfer_function.opacity_points[2]
    assert (x, a) == (0.4, 0.0)
    np.testing.assert_array_equal(state.transfer_function.opacity_points[:, 0], [0.0, 0.4, 0.4, 0.6, 1.0])


def test_end_points_move_within_the_axis(qtbot, editor, state):
    drag(qtbot, editor.curve, editor.point_positions()[-1], QPoint(editor.curve.width() + 50, 0))
    assert tuple(state.transfer_function.opacity_points[-1]) == (1.0, 1.0)


def test_right_click_and_delete_remove_points_but_not_the_ends(qtbot, editor, state, history):
    curve = editor.curve
    qtbot.mouseClick(curve, Qt.RightButton, pos=editor.point_positions()[1])  # (0.4, 0)
    np.testing.assert_array_equal(state.transfer_function.opacity_points[:, 0], [0.0, 0.5, 0.6, 1.0])
    qtbot.mouseClick(curve, Qt.LeftButton, pos=editor.point_positions()[1])  # select (0.5, 0.7)
    assert curve.selected == 1
    qtbot.keyClick(curve, Qt.Key_Delete)
    np.testing.assert_array_equal(state.transfer_function.opacity_points[:, 0], [0.0, 0.6, 1.0])
    qtbot.mouseClick(curve, Qt.RightButton, pos=editor.point_positions()[0])
    qtbot.mouseClick(curve, Qt.LeftButton, pos=editor.point_positions()[-1])
    qtbot.keyClick(curve, Qt.Key_Delete)
    np.testing.assert_array_equal(state.transfer_function.opacity_points[:, 0], [0.0, 0.6, 1.0])
    assert history.stack.count() == 2  # the two deletions; selecting and refusals record nothing


def test_edits_from_code_and_replaced_tfs_show_up(qtbot, editor, state):
    curve = editor.curve
    state.transfer_function.set_opacity_points([[0.0, 0.0], [1.0, 1.0]])
    assert editor.point_positions() == [curve.position_of(0.0, 0.0), curve.position_of(1.0, 1.0)]
    assert editor.point_positions()[1] == QPoint(curve.width() - MARGIN, TOP)

    old = state.transfer_function
    new = TransferFunction1D([[-1.0, 1, 0, 0], [3.0, 0, 0, 1]], [[-1.0, 0.2], [1.0, 0.2], [3.0, 0.9]], 0.5)
    state.set_transfer_function(new)
    assert (curve.axis.lo, curve.axis.hi) == (-1.0, 3.0)  # the TF's range covers the data's
    assert editor.point_positions() == [curve.position_of(x, a) for x, a in new.opacity_points]
    assert (editor.min_spin.value(), editor.max_spin.value()) == (-1.0, 3.0)
    assert editor.unit_spin.value() == 0.5
    assert [p.x() for p in editor.stop_positions()] == [MARGIN, editor.color_bar.width() - MARGIN]
    # gestures now edit the new object, and leave the old one alone
    old_points = old.opacity_points
    qtbot.mouseClick(curve, Qt.LeftButton, pos=curve.position_of(2.0, 0.5))
    assert len(new.opacity_points) == 4
    np.testing.assert_array_equal(old.opacity_points, old_points)


def test_histogram_is_the_volumes_and_log_is_a_toggle(editor, state):
    assert editor.curve.histogram is value_histogram(state.volume)
    assert editor.curve.log_counts and editor.log_check.isChecked()  # log by default (issue 23)
    editor.grab()  # paints with log heights
    editor.log_check.setChecked(False)
    assert not editor.curve.log_counts
    editor.grab()


def test_log_counts_by_default_show_the_values_beside_a_dominant_background(editor, state):
    """Issue 23: CT-like data, 95 % of the voxels at one value, drew an empty box in linear counts."""
    values = np.zeros((20, 20, 20), np.float32)
    values.flat[::20] = np.linspace(0.1, 1.0, values.size // 20)  # 5 % of the voxels spread out
    volume = UniformVolume(values)
    state.load(volume, default_transfer_function(volume), default_camera(volume))
    histogram = editor.curve.histogram
    visible_log = np.count_nonzero(histogram.heights(editor.curve.log_counts) > 0.05)
    visible_linear = np.count_nonzero(histogram.heights(False) > 0.05)
    assert visible_linear <= 1 < 10 <= visible_log


def test_a_new_volume_brings_its_histogram(editor, state):
    volume = marschner_lobb(9)
    state.load(volume, default_transfer_function(volume), default_camera(volume))
    assert editor.curve.histogram is value_histogram(volume)


def test_a_large_volumes_histogram_comes_from_the_background_and_only_the_newest(
    qtbot, editor, state, monkeypatch
):
    """A 256^3 grid's histogram held the GUI thread 0.15-0.85 s at every open: large volumes now
    get it from a pool thread, the plot showing the TF meanwhile; a volume replaced before its
    histogram is ready never shows it."""
    import volren.app.tf_editor.one_d.background_histogram as background

    monkeypatch.setattr(background, "BACKGROUND_VALUES", 100)  # "large": above 100 values
    first, second = marschner_lobb(9), marschner_lobb(11)
    state.load(first, default_transfer_function(first), default_camera(first))
    state.load(second, default_transfer_function(second), default_camera(second))
    qtbot.waitUntil(lambda: editor.curve.histogram is not None, timeout=10_000)
    assert editor.curve.histogram is value_histogram(second)
    assert editor._histograms.wait()
    qtbot.wait(50)  # any answer for the first volume would have been delivered by now
    assert editor.curve.histogram is value_histogram(second)


# ---------------------------------------------------------------------------- colour bar
def test_click_on_the_bar_adds_a_stop_in_the_colour_shown_there(qtbot, editor, state, history):
    bar = editor.color_bar
    tf = state.transfer_function
    pos = bar.position_of(0.6)
    value = bar.value_at(pos.x())
    shown, _ = tf.sample([value])
    qtbot.mouseClick(bar, Qt.LeftButton, pos=pos)
    points = tf.color_points
    assert len(points) == 6
    added = points[np.argmin(np.abs(points[:, 0] - value))]
    assert added[0] == pytest.approx(0.6, abs=value_per_pixel(editor))
    np.testing.assert_allclose(added[1:], shown[0], atol=1e-4)  # QColor keeps 16 bits a channel
    assert history.stack.count() == 1


def test_dragging_a_stop_moves_it_between_its_neighbours(qtbot, editor, state, history):
    bar = editor.color_bar
    before = state.transfer_function.color_points  # viridis at 0, .25, .5, .75, 1
    drag(qtbot, bar, editor.stop_positions()[1], bar.position_of(0.4))
    after = state.transfer_function.color_points
    assert after[1, 0] == pytest.approx(0.4, abs=value_per_pixel(editor))
    np.testing.assert_array_equal(after[1, 1:], before[1, 1:])
    assert history.stack.count() == 1
    drag(qtbot, bar, editor.stop_positions()[1], bar.position_of(0.9))
    assert state.transfer_function.color_points[1, 0] == 0.5  # stopped by the next stop
    history.undo()
    history.undo()
    np.testing.assert_array_equal(state.transfer_function.color_points, before)


def test_double_click_picks_the_stop_colour_through_choose_color(qtbot, editor, state):
    bar = editor.color_bar
    asked: list[QColor] = []

    def choose(initial: QColor) -> QColor:
        asked.append(initial)
        return QColor(255, 0, 0)

    bar.choose_color = choose
    before = state.transfer_function.color_points
    qtbot.mouseDClick(bar, Qt.LeftButton, pos=editor.stop_positions()[2])
    points = state.transfer_function.color_points
    np.testing.assert_array_equal(points[2], [before[2, 0], 1.0, 0.0, 0.0])
    assert len(asked) == 1
    assert asked[0].redF() == pytest.approx(before[2, 1], abs=1e-4)
    bar.choose_color = lambda initial: None  # cancelled: nothing changes
    qtbot.mouseDClick(bar, Qt.LeftButton, pos=editor.stop_positions()[3])
    np.testing.assert_array_equal(state.transfer_function.color_points, points)


def test_right_click_removes_inner_stops_only(qtbot, editor, state):
    bar = editor.color_bar
    qtbot.mouseClick(bar, Qt.RightButton, pos=editor.stop_positions()[1])
    np.testing.assert_array_equal(state.transfer_function.color_points[:, 0], [0.0, 0.5, 0.75, 1.0])
    qtbot.mouseClick(bar, Qt.RightButton, pos=editor.stop_positions()[-1])
    qtbot.mouseClick(bar, Qt.LeftButton, pos=editor.stop_positions()[0])
    qtbot.keyClick(bar, Qt.Key_Delete)
    np.testing.assert_array_equal(state.transfer_function.color_points[:, 0], [0.0, 0.5, 0.75, 1.0])


# ---------------------------------------------------------------------------- presets, range, unit
def test_preset_changes_colours_over_the_range_and_keeps_opacity(editor, state, history):
    tf = state.transfer_function
    opacity = tf.opacity_points
    tf.rescale(-2.0, 6.0)
    history.stack.clear()
    editor.preset_box.setCurrentText("plasma")
    points = tf.color_points
    np.testing.assert_allclose(points, preset_color_points("plasma", -2.0, 6.0))
    assert (points[0, 0], points[-1, 0]) == (-2.0, 6.0)
    np.testing.assert_allclose(points[-1, 1:], [0.940015, 0.975158, 0.131326], atol=1e-6)  # plasma's end
    np.testing.assert_allclose(tf.opacity_points[:, 1], opacity[:, 1])
    assert editor.preset_box.currentText() == PRESET_PLACEHOLDER  # ready to choose again
    assert history.stack.count() == 1
    index = editor.preset_box.findText("plasma")
    assert editor.preset_box.itemIcon(index).isNull()  # swatches wait for the list to open
    editor.preset_box.showPopup()
    editor.preset_box.hidePopup()
    assert not editor.preset_box.itemIcon(index).isNull()


def test_presets_follow_their_sources():
    colormaps = pytest.importorskip("matplotlib").colormaps

    x = np.arange(256) / 255
    for name, tolerance in (("viridis", 0.04), ("cividis", 0.04), ("jet", 1e-9), ("bone", 1e-9)):
        stops = unit_stops({"jet": "Jet", "bone": "Bone"}.get(name, name))
        ours = np.stack([np.interp(x, stops[:, 0], stops[:, c]) for c in (1, 2, 3)], axis=-1)
        assert np.abs(ours - colormaps[name](np.arange(256))[:, :3]).max() <= tolerance, name
    cool_warm = unit_stops("Cool to Warm")
    assert len(cool_warm) == 17
    paraview_nodes = [[0, 0.2314, 0.2980, 0.7529], [0.5, 0.865, 0.865, 0.865], [1, 0.7059, 0.0157, 0.1490]]
    np.testing.assert_allclose(cool_warm[[0, 8, 16]], paraview_nodes, atol=1e-3)
    # Moreland's diverging map is brighter half way between blue and white than a straight RGB blend
    assert cool_warm[4, 1:].sum() > (0.5 * (cool_warm[0, 1:] + cool_warm[8, 1:])).sum() + 0.1
    np.testing.assert_allclose(unit_stops("Black-Body Radiation")[:, 0], [0.0, 0.4, 0.8, 1.0])
    for name in PRESET_NAMES:
        stops = unit_stops(name)
        assert stops[0, 0] == 0.0 and stops[-1, 0] == 1.0 and np.all(np.diff(stops[:, 0]) > 0), name
    with pytest.raises(VolrenError, match="no colour map named 'nope'"):
        apply_preset(TransferFunction1D.ramp(0, 1), "nope")


def test_the_preset_data_is_what_the_generator_writes(tmp_path):
    """colormap_presets.json is generated (scripts/make_colormap_presets.py): regenerating it from
    matplotlib and ParaView's nodes gives the same stops, so the data and its sources agree."""
    pytest.importorskip("matplotlib")
    script = Path(__file__).resolve().parents[2] / "scripts" / "make_colormap_presets.py"
    spec = importlib.util.spec_from_file_location("make_colormap_presets", script)
    generator = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(generator)
    generator.main([str(tmp_path / "presets.json")])
    fresh = json.loads((tmp_path / "presets.json").read_text())["presets"]
    assert tuple(fresh) == PRESET_NAMES
    for name in PRESET_NAMES:  # to rounding: other matplotlib or VTK builds may differ in the last digits
        np.testing.assert_allclose(unit_stops(name), fresh[name], atol=1e-6, err_msg=name)


def test_range_boxes_rescale_the_tf(editor, state):
    tf = state.transfer_function
    editor.max_spin.setValue(2.0)
    assert tf.value_range == (0.0, 2.0)
    assert tf.opacity_points[2, 0] == pytest.approx(1.0)  # the 0.5 peak doubled
    editor.min_spin.setValue(1.0)
    assert tf.value_range == (1.0, 2.0)
    assert tf.opacity_points[2, 0] == pytest.approx(1.5)
    editor.min_spin.setValue(3.0)  # above the maximum: refused, the box shows the range again
    assert tf.value_range == (1.0, 2.0)
    assert editor.min_spin.value() == 1.0
    editor.reset_range_button.click()
    assert tf.value_range == state.volume.value_range
    assert (editor.curve.axis.lo, editor.curve.axis.hi) == state.volume.value_range


def test_unit_distance_box_sets_the_tf(editor, state):
    editor.unit_spin.setValue(0.2)
    assert state.transfer_function.opacity_unit_distance == pytest.approx(0.2)
    state.transfer_function.set_opacity_unit_distance(0.0125)
    assert editor.unit_spin.value() == pytest.approx(0.0125)


# ---------------------------------------------------------------------------- files
def test_save_then_open_gives_an_equal_tf(qtbot, editor, state, history, tmp_path):
    original = state.transfer_function.copy()
    editor.get_save_path = lambda: str(tmp_path / "mine")  # no suffix: .json is added
    qtbot.mouseClick(editor.save_button, Qt.LeftButton)
    path = tmp_path / "mine.json"
    assert load_transfer_function(path) == original
    editor.apply_preset("Jet")
    state.transfer_function.set_opacity_points([[0.0, 1.0], [1.0, 1.0]])
    assert state.transfer_function != original
    editor.get_open_path = lambda: str(path)
    qtbot.mouseClick(editor.open_button, Qt.LeftButton)
    assert state.transfer_function == original
    history.undo()  # opening a file is one undo step
    np.testing.assert_array_equal(state.transfer_function.opacity_points, [[0.0, 1.0], [1.0, 1.0]])


def test_a_paraview_preset_brings_its_colours_over_the_current_range(editor, state, tmp_path):
    path = tmp_path / "presets.json"
    preset = {"Name": "Red to blue", "ColorSpace": "RGB", "RGBPoints": [-1, 1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 1]}
    path.write_text(json.dumps([preset]))
    opacity = state.transfer_function.opacity_points
    unit = state.transfer_function.opacity_unit_distance
    assert editor.open_file(path)
    tf = state.transfer_function
    np.testing.assert_allclose(tf.color_points, [[0.0, 1, 0, 0], [0.5, 0, 1, 0], [1.0, 0, 0, 1]])
    np.testing.assert_array_equal(tf.opacity_points, opacity)
    assert tf.opacity_unit_distance == unit

    preset["Points"] = [-1, 0.0, 0.5, 0.0, 1, 0.8, 0.5, 0.0]  # with its own opacity: that comes too
    path.write_text(json.dumps([preset]))
    assert editor.open_file(path)
    np.testing.assert_allclose(state.transfer_function.opacity_points, [[0.0, 0.0], [1.0, 0.8]], atol=1e-9)


@pytest.mark.parametrize(
    "content, problem",
    [
        ("{not json", "invalid JSON"),
        ('{"version": 1, "kind": "1d", "color": []}', "opacity"),
        (None, "no such file"),
    ],
)
def test_a_bad_file_is_reported_in_one_line_naming_it(qtbot, editor, state, tmp_path, content, problem):
    path = tmp_path / "bad.json"
    if content is not None:
        path.write_text(content)
    before = state.transfer_function
    with qtbot.waitSignal(editor.errorOccurred, timeout=1000) as blocker:
        assert not editor.open_file(path)
    title, message = blocker.args
    assert title == "Cannot open the transfer function"
    assert str(path) in message and problem in message and "\n" not in message
    assert state.transfer_function is before


def test_a_save_that_fails_is_reported(qtbot, editor, tmp_path):
    with qtbot.waitSignal(editor.errorOccurred, timeout=1000) as blocker:
        assert not editor.save_file(tmp_path / "missing" / "tf.json")
    assert blocker.args[0] == "Cannot save the transfer function"
    assert "missing" in blocker.args[1] and "\n" not in blocker.args[1]


def test_a_2d_tf_file_goes_into_the_state(editor, state, tmp_path):
    tf2 = TransferFunction2D(
        (0.0, 1.0), (0.0, 2.0), [TFWidget.gaussian((0.5, 1.0), (0.1, 0.5), (1, 0, 0), 0.5)]
    )
    path = tmp_path / "two.json"
    path.write_text(json.dumps(tf2.to_dict()))
    assert editor.open_file(path)
    assert state.transfer_function.dims == 2
    assert editor.pages.currentWidget() is editor.page_2d


# ---------------------------------------------------------------------------- 2D transfer functions
def test_a_2d_tf_offers_a_1d_one(qtbot, editor, state):
    """Back to the 1D TF the 2D one replaced (issue 23: the user's work); a scene opened with a
    2D TF has none, and gets the volume's default."""
    edited = state.transfer_function
    state.set_transfer_function(TransferFunction2D((0.0, 1.0), (0.0, 2.0)))
    assert editor.pages.currentWidget() is editor.page_2d
    assert editor.point_positions() == []
    assert editor.use_1d_button.isEnabled()
    qtbot.mouseClick(editor.use_1d_button, Qt.LeftButton)
    assert state.transfer_function is edited
    assert editor.pages.currentWidget() is editor.page_1d
    state.load(state.volume, TransferFunction2D((0.0, 1.0), (0.0, 2.0)), state.camera)
    qtbot.mouseClick(editor.use_1d_button, Qt.LeftButton)
    assert state.transfer_function == default_transfer_function(state.volume)


def test_without_a_volume_the_1d_button_is_disabled(make_editor):
    state = ViewState()
    editor = make_editor(state)
    assert not editor.page_1d.isEnabled() and not editor.save_button.isEnabled()
    state.set_transfer_function(TransferFunction2D((0.0, 1.0), (0.0, 2.0)))
    assert editor.pages.currentWidget() is editor.page_2d
    assert not editor.use_1d_button.isEnabled()


def test_the_selected_points_value_and_opacity_are_typed(qtbot, editor, state):
    """Issue 23: numeric entry of the selected point; it follows the selection and the TF's edits,
    and a typed value stays between the neighbours."""
    entry = editor.point_entry
    curve = editor.curve
    tf = state.transfer_function
    assert not entry.isEnabled()  # nothing selected
    points = tf.opacity_points
    index = len(points) // 2
    qtbot.mouseClick(curve, Qt.LeftButton, pos=curve.point_positions()[index])
    assert curve.selected == index and entry.isEnabled()
    assert entry.value.value() == pytest.approx(points[index, 0]) and entry.opacity.value() == pytest.approx(
        points[index, 1], abs=1e-3
    )
    left, right = points[index - 1, 0], points[index + 1, 0]
    target = left + 0.25 * (right - left)
    entry.value.setValue(target)
    entry.opacity.setValue(0.42)
    entry.opacity.editingFinished.emit()
    np.testing.assert_allclose(tf.opacity_points[index], [target, 0.42])
    entry.value.setValue(right + 10.0)  # beyond the right neighbour: stops there
    entry.value.editingFinished.emit()
    assert tf.opacity_points[index, 0] == pytest.approx(right)
    moved = tf.opacity_points.copy()
    moved[index, 1] = 0.1
    tf.set_opacity_points(moved)  # an edit elsewhere shows in the fields
    assert entry.opacity.value() == pytest.approx(0.1)
    curve.selected = None
    assert not entry.isEnabled()


# ---------------------------------------------------------------------------- tissue presets and shift
def _ct_state() -> ViewState:
    from volren.samples import shepp_logan_ct

    s = ViewState()
    volume = shepp_logan_ct(24)
    s.load(volume, default_transfer_function(volume), default_camera(volume))
    return s


def test_tissue_presets_fit_the_data_ct_ones_only_on_hounsfield_units(make_editor, state, qtbot):
    """Issue 23: opacity presets for CT (in HU) and MR, offered only where they fit, saying why."""
    from volren.app.core.opacity_presets import OPACITY_PRESET_NAMES, robust_range

    editor = make_editor(state)  # Marschner-Lobb, values 0..1: not HU
    model = editor.tissue_box.model()
    ct_items = [i for i, n in enumerate(OPACITY_PRESET_NAMES, 1) if n.startswith("CT")]
    assert ct_items and all(not model.item(i).isEnabled() for i in ct_items)
    assert "Hounsfield" in model.item(ct_items[0]).toolTip()
    mr = OPACITY_PRESET_NAMES.index("MR default") + 1
    assert model.item(mr).isEnabled()
    editor.tissue_box.setCurrentIndex(mr)
    tf = state.transfer_function
    lo, hi = robust_range(state.volume)
    assert editor.tissue_box.currentIndex() == 0  # an action: the box goes back to its placeholder
    np.testing.assert_allclose(tf.opacity_points[:, 0], lo + np.array([0, 0.15, 0.4, 1]) * (hi - lo))
    assert tf.opacity_unit_distance == state.volume.characteristic_length
    ct = _ct_state()
    ct_editor = make_editor(ct)
    assert all(ct_editor.tissue_box.model().item(i).isEnabled() for i in ct_items)
    assert ct_editor.apply_tissue_preset("CT bone")
    bone = ct.transfer_function
    assert float(bone.sample(-1000.0)[1]) == 0.0 and float(bone.sample(150.0)[1]) == 0.0
    assert float(bone.sample(700.0)[1]) == pytest.approx(0.8)  # HU used as they are
    errors = []
    editor.errorOccurred.connect(lambda title, text: errors.append(text))
    assert not editor.apply_tissue_preset("CT lung")
    assert "CT lung: CT presets are in Hounsfield units" in errors[0]


def test_the_shift_sliders_travel_is_half_the_data_range_each_way_in_steps_of_a_thousandth(
    make_editor, qtbot
):
    """The whole slider spans the data range (half of it each way), so a pixel of a drag is a
    fraction of a percent; the arrow keys move a thousandth of the range, Page Up/Down a hundredth."""
    state = _ct_state()  # -1000..1000 HU
    editor = make_editor(state)
    editor.apply_tissue_preset("CT soft tissue")
    preset = state.transfer_function.copy()
    slider = editor.shift_slider

    def moved() -> float:
        return float(state.transfer_function.opacity_points[0, 0] - preset.opacity_points[0, 0])

    slider.setFocus()
    qtbot.keyClick(slider, Qt.Key_Right)
    assert moved() == pytest.approx(2.0) and editor.shift_label.text() == "+2"
    qtbot.keyClick(slider, Qt.Key_PageUp)
    assert moved() == pytest.approx(22.0)
    qtbot.keyClick(slider, Qt.Key_End)
    assert moved() == pytest.approx(1000.0) and editor.shift_label.text() == "+1000"
    qtbot.keyClick(slider, Qt.Key_Home)
    assert moved() == pytest.approx(-1000.0) and (slider.minimum(), slider.maximum()) == (-500, 500)


def test_the_shift_slider_slides_the_whole_tf_and_a_drag_is_one_undo_step(make_editor, qtbot):
    state = _ct_state()
    history = TFHistory(state)
    try:
        editor = make_editor(state)
        editor.apply_tissue_preset("CT soft tissue")
        preset = state.transfer_function.copy()
        step = editor.shift_step()
        assert step == pytest.approx(2000 / 1000)  # the phantom spans -1000..1000 HU
        slider = editor.shift_slider
        recorded = history.stack.count()
        slider.sliderPressed.emit()
        for value in (3, 9, 15):
            slider.setValue(value)
        slider.sliderReleased.emit()
        tf = state.transfer_function
        np.testing.assert_allclose(tf.opacity_points[:, 0], preset.opacity_points[:, 0] + 15 * step)
        np.testing.assert_allclose(tf.color_points[:, 0], preset.color_points[:, 0] + 15 * step)
        np.testing.assert_array_equal(tf.opacity_points[:, 1], preset.opacity_points[:, 1])
        assert history.stack.count() == recorded + 1  # the drag is one step
        assert slider.value() == 15 and editor.shift_label.text() == "+30"  # kept after the release
        slider.setValue(-5)  # a keyboard step: from the same base
        np.testing.assert_allclose(
            state.transfer_function.opacity_points[:, 0], preset.opacity_points[:, 0] - 5 * step
        )
        state.transfer_function.set_opacity_unit_distance(2.0)  # another edit: the slider starts from here
        assert slider.value() == 0 and editor.shift_label.text() == "0"
        history.undo()
        assert slider.value() == 0
    finally:
        history.detach()
