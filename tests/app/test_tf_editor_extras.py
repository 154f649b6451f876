"""Issue 23's editor extras, driven through real widgets: the selected colour stop typed and picked,
the searchable colour-map browser with ParaView's maps (and the script that imports them), the 1D
editor's zoomable value axis, and the 2D editor's hover readout.

Each checks the model's numbers against an oracle computed here: the stop typed, the map's stops
spread over the TF's range, the zoomed axis from the wheel's centre and factor, the value under
the mouse, the histogram's bin.
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest
from PyQt5.QtCore import QEvent, QPoint, QPointF, QRect, Qt
from PyQt5.QtGui import QColor, QWheelEvent
from PyQt5.QtWidgets import QApplication, QDialogButtonBox, QWidget

from tests.app.widget_input import drag, hover, shown
from volren.api import default_transfer_function
from volren.app.core.colormap_presets import (
    PARAVIEW_FILE,
    PARAVIEW_SUFFIX,
    PRESET_NAMES,
    all_preset_names,
    preset_color_points,
    unit_stops,
)
from volren.app.core.joint_histogram import joint_histogram
from volren.app.core.state import ViewState, default_camera
from volren.app.tf_editor.one_d.editor import PRESET_PLACEHOLDER, TransferFunction1DEditor
from volren.app.tf_editor.one_d.point_canvas import MARGIN, ZOOM_STEP
from volren.app.tf_editor.one_d.preset_browser import SWATCH, swatch_image
from volren.app.tf_editor.two_d.editor import TransferFunction2DEditor
from volren.app.tf_editor.two_d.widget_canvas import MARGINS
from volren.model.transfer_function_2d import TFWidget, TransferFunction2D
from volren.model.value_histogram import value_histogram
from volren.model.volume import UniformVolume

REPO = Path(__file__).resolve().parents[2]


# ---------------------------------------------------------------------------- fixtures and helpers
# `state` (the Marschner-Lobb sample: colours viridis at 0, .25, .5, .75, 1; opacity points at 0,
# .4, .5, .6, 1; data inside [0, 1]) and `history` come from conftest
@pytest.fixture
def editor(qtbot, state) -> TransferFunction1DEditor:
    return shown(qtbot, TransferFunction1DEditor(state), (320, 420))


def wheel(widget: QWidget, pos: QPoint, notches: float = 1.0) -> None:
    p = QPointF(pos)
    event = QWheelEvent(p, p, QPoint(0, 0), QPoint(0, round(120 * notches)), Qt.NoButton, Qt.NoModifier,
                        Qt.NoScrollPhase, False)  # fmt: skip
    QApplication.sendEvent(widget, event)


def type_into(qtbot, spin, text: str) -> None:
    spin.lineEdit().selectAll()
    qtbot.keyClicks(spin.lineEdit(), text)
    qtbot.keyClick(spin, Qt.Key_Return)


def select_stop(qtbot, editor: TransferFunction1DEditor, index: int) -> None:
    qtbot.mouseClick(editor.color_bar, Qt.LeftButton, pos=editor.stop_positions()[index])
    assert editor.color_bar.selected == index


# ---------------------------------------------------------------------------- colour stop entry
def test_the_selected_stops_value_is_typed_as_one_undo_step(qtbot, editor, state, history):
    entry = editor.color_entry
    tf = state.transfer_function
    assert not entry.isEnabled()  # nothing selected
    before = tf.color_points
    select_stop(qtbot, editor, 1)  # a click that selects moves nothing
    assert history.stack.count() == 0
    assert entry.isEnabled() and entry.value.value() == before[1, 0] == 0.25
    assert (entry.value.minimum(), entry.value.maximum()) == (0.0, 0.5)  # between its neighbours
    type_into(qtbot, entry.value, "0.3125")
    expected = before.copy()
    expected[1, 0] = 0.3125
    np.testing.assert_array_equal(tf.color_points, expected)
    assert history.stack.count() == 1
    entry.value.setValue(0.9)  # past the next stop (the box refuses typing it): stops there
    entry.value.editingFinished.emit()
    assert tf.color_points[1, 0] == 0.5
    assert history.stack.count() == 2
    history.undo()
    history.undo()
    np.testing.assert_array_equal(state.transfer_function.color_points, before)
    assert not entry.isEnabled()  # undo replaced the TF: the selection went with it


def test_the_selected_stops_colour_is_picked_as_one_undo_step(qtbot, editor, state, history):
    entry = editor.color_entry
    tf = state.transfer_function
    before = tf.color_points
    select_stop(qtbot, editor, 2)
    assert entry.color_button.text() == QColor.fromRgbF(*before[2, 1:]).name()
    asked: list[QColor] = []
    chosen = QColor.fromRgbF(0.2, 0.4, 0.6)

    def choose(initial: QColor) -> QColor:
        asked.append(initial)
        return chosen

    editor.color_bar.choose_color = choose
    qtbot.mouseClick(entry.color_button, Qt.LeftButton)
    expected = before.copy()
    expected[2, 1:] = chosen.redF(), chosen.greenF(), chosen.blueF()
    np.testing.assert_array_equal(tf.color_points, expected)
    assert asked[0].name() == QColor.fromRgbF(*before[2, 1:]).name()  # the dialog starts at the stop's colour
    assert entry.color_button.text() == chosen.name()
    assert history.stack.count() == 1
    editor.color_bar.choose_color = lambda initial: None  # cancelled: nothing changes
    qtbot.mouseClick(entry.color_button, Qt.LeftButton)
    np.testing.assert_array_equal(tf.color_points, expected)
    assert history.stack.count() == 1


def test_the_stop_fields_follow_edits_and_leaving_them_changes_nothing(qtbot, editor, state, history):
    tf = state.transfer_function
    select_stop(qtbot, editor, 3)
    points = tf.color_points
    points[3] = [0.623456789, 1.0, 0.5, 0.0]  # more digits than the box shows
    tf.set_color_points(points)  # an edit elsewhere shows in the fields, and writes nothing back
    assert history.stack.count() == 1
    entry = editor.color_entry
    assert entry.value.value() == pytest.approx(0.623457)
    assert entry.color_button.text() == QColor.fromRgbF(1.0, 0.5, 0.0).name()
    entry.value.setFocus()
    entry.value.editingFinished.emit()  # focus leaves the box untouched: the exact value stays
    np.testing.assert_array_equal(tf.color_points, points)
    assert history.stack.count() == 1


def test_the_opacity_point_fields_keep_an_untyped_value_exactly(qtbot, editor, state, history):
    tf = state.transfer_function
    points = tf.opacity_points
    points[2, 0] = 0.512345678  # more digits than the box shows
    tf.set_opacity_points(points)
    qtbot.mouseClick(editor.curve, Qt.LeftButton, pos=editor.point_positions()[2])
    type_into(qtbot, editor.point_entry.opacity, "0.25")  # only the opacity typed
    np.testing.assert_array_equal(tf.opacity_points[2], [0.512345678, 0.25])


# ---------------------------------------------------------------------------- colour-map browser
def _paraview_maps() -> dict[str, list[list[float]]]:
    return json.loads(PARAVIEW_FILE.read_text(encoding="utf-8"))


def test_the_paraview_data_holds_normalised_rounded_ramps():
    maps = _paraview_maps()
    assert len(maps) > 100
    text = PARAVIEW_FILE.read_text(encoding="utf-8")
    assert "\n" not in text and text.count(" ") == sum(name.count(" ") for name in maps)  # no whitespace
    for name, rows in maps.items():
        stops = np.array(rows)
        assert stops.shape[1] == 4 and len(stops) >= 2, name
        assert stops[0, 0] == 0.0 and stops[-1, 0] == 1.0 and np.all(np.diff(stops[:, 0]) >= 0), name
        assert np.all((stops[:, 1:] >= 0) & (stops[:, 1:] <= 1)), name
        np.testing.assert_array_equal(stops, np.round(stops, 4), err_msg=name)
    # RGB-space maps keep ParaView's nodes; Cool to Warm (Diverging) passes through its three
    assert maps["X Ray"] == [[0, 1, 1, 1], [1, 0, 0, 0]]
    cool_to_warm = np.array(maps["Cool to Warm"])
    nodes = [[0, 0.2314, 0.298, 0.7529], [0.5, 0.865, 0.865, 0.865], [1, 0.7059, 0.0157, 0.149]]
    for x, *rgb in nodes:
        np.testing.assert_allclose([np.interp(x, cool_to_warm[:, 0], cool_to_warm[:, c]) for c in (1, 2, 3)],
                                   rgb, atol=1e-4)  # fmt: skip


def test_the_names_are_the_curated_ones_then_paraviews_each_once():
    names = all_preset_names()
    paraview = _paraview_maps()
    assert names[: len(PRESET_NAMES)] == PRESET_NAMES
    assert len(names) == len(set(names)) == len(PRESET_NAMES) + len(paraview)
    curated = {n.casefold() for n in PRESET_NAMES}
    listed = [n.removesuffix(PARAVIEW_SUFFIX) for n in names[len(PRESET_NAMES) :]]
    assert sorted(listed) == sorted(paraview)
    assert "Viridis (ParaView)" in names and "Viridis" not in names and "viridis" in names
    assert all((n + PARAVIEW_SUFFIX in names) == (n.casefold() in curated) for n in paraview)
    np.testing.assert_array_equal(unit_stops("Viridis (ParaView)"), paraview["Viridis"])


def test_the_import_script_converts_a_paraview_preset_file(tmp_path):
    pytest.importorskip("vtkmodules")
    spec = importlib.util.spec_from_file_location(
        "import_paraview_colormaps", REPO / "scripts" / "import_paraview_colormaps.py"
    )
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    source = tmp_path / "ColorMaps.json"
    source.write_text(  # ParaView writes trailing commas
        '[{"Name": "Red to blue", "ColorSpace": "RGB", "RGBPoints": [-1, 1, 0, 0, 0, 0, 1, 0, 3, 0, 0, 1],},'
        ' {"Name": "Categories", "IndexedColors": [1, 0, 0, 0, 1, 0]},'
        ' {"Name": "Also indexed", "RGBPoints": [0, 0, 0, 0, 1, 1, 1, 1], "IndexedColors": [1, 0, 0]},'
        ' {"Name": "Thirds", "ColorSpace": "RGB", "RGBPoints": [0, 0, 0, 0, 3, 0.333333, 0.666666, 1]},]'
    )
    out = tmp_path / "maps.json"
    assert script.main([str(source), str(out)]) == 0
    text = out.read_text()
    assert text == ('{"Red to blue":[[0,1,0,0],[0.25,0,1,0],[1,0,0,1]],'
                    '"Thirds":[[0,0,0,0],[1,0.3333,0.6667,1]]}')  # fmt: skip


def test_the_browser_filters_by_name_case_insensitively(qtbot, editor):
    browser = editor.open_preset_browser()
    qtbot.waitExposed(browser)
    assert browser.visible_names() == list(all_preset_names())
    qtbot.keyClicks(browser.search, "BLue")
    expected = [n for n in all_preset_names() if "blue" in n.lower()]
    assert len(all_preset_names()) > len(expected) > 10
    assert browser.visible_names() == expected
    assert browser.count_label.text() == f"{len(expected)} of {len(all_preset_names())} colour maps"
    browser.search.clear()
    qtbot.keyClicks(browser.search, "no such map")
    assert browser.visible_names() == []
    assert not browser.buttons.button(QDialogButtonBox.Ok).isEnabled()
    browser.reject()


def _item_center(browser, name: str) -> QPoint:
    item = browser.item(name)
    browser.list.scrollToItem(item)
    return browser.list.visualItemRect(item).center()


def test_double_click_applies_a_paraview_map_over_the_tf_range(qtbot, editor, state, history):
    tf = state.transfer_function
    tf.rescale(-2.0, 6.0)
    opacity = tf.opacity_points
    history.stack.clear()
    box = editor.preset_box
    box.setCurrentIndex(box.count() - 1)  # "Browse colour maps…", the combo box's last entry
    browser = editor.preset_browser
    assert browser is not None and browser.isVisible()
    assert box.currentText() == PRESET_PLACEHOLDER
    qtbot.keyClicks(browser.search, "rainbow uniform")
    assert browser.visible_names() == ["Rainbow Uniform"]
    at = _item_center(browser, "Rainbow Uniform")
    qtbot.mouseClick(browser.list.viewport(), Qt.LeftButton, pos=at)  # a double-click's first click
    qtbot.mouseDClick(browser.list.viewport(), Qt.LeftButton, pos=at)
    assert not browser.isVisible()
    stops = np.array(_paraview_maps()["Rainbow Uniform"])
    expected = np.column_stack([-2.0 + 8.0 * stops[:, 0], stops[:, 1:]])
    np.testing.assert_allclose(tf.color_points, expected, rtol=0, atol=1e-12)
    assert (tf.color_points[0, 0], tf.color_points[-1, 0]) == (-2.0, 6.0)
    np.testing.assert_array_equal(tf.opacity_points, opacity)
    assert history.stack.count() == 1


def test_ok_applies_the_selected_map_and_cancel_changes_nothing(qtbot, editor, state, history):
    tf = state.transfer_function
    before = tf.color_points
    browser = editor.open_preset_browser()
    qtbot.mouseClick(browser.list.viewport(), Qt.LeftButton, pos=_item_center(browser, "magma"))
    assert browser.chosen() == "magma"
    qtbot.mouseClick(browser.buttons.button(QDialogButtonBox.Cancel), Qt.LeftButton)
    assert not browser.isVisible()
    np.testing.assert_array_equal(tf.color_points, before)
    assert history.stack.count() == 0

    browser = editor.open_preset_browser()
    assert browser.chosen() is None and browser.search.text() == ""  # opens afresh
    qtbot.mouseClick(browser.list.viewport(), Qt.LeftButton, pos=_item_center(browser, "magma"))
    assert browser.buttons.button(QDialogButtonBox.Ok).isEnabled()
    qtbot.mouseClick(browser.buttons.button(QDialogButtonBox.Ok), Qt.LeftButton)
    assert not browser.isVisible()
    np.testing.assert_array_equal(tf.color_points, preset_color_points("magma", *tf.value_range))
    assert history.stack.count() == 1


def rows_in_view(browser) -> set[str]:
    """The names of the rows the browser's list shows inside its viewport now."""
    viewport = browser.list.viewport().rect()
    shown = browser.visible_names()
    return {name for name in shown if browser.list.visualItemRect(browser.item(name)).intersects(viewport)}


def test_opening_the_browser_draws_only_the_swatches_in_view(qtbot, editor):
    """What kept opening the browser quick: a swatch is drawn when its row first paints, so the
    dialog draws the rows in view, not every map's image."""
    browser = editor.open_preset_browser()
    qtbot.waitExposed(browser)
    browser.list.viewport().grab()  # paints the list now
    in_view = rows_in_view(browser)
    assert 0 < len(in_view) < len(all_preset_names()) / 3
    # and the last row, which Qt measures for the rows' common height (uniform item sizes)
    assert set(browser.delegate.icons) == in_view | {all_preset_names()[-1]}
    browser.list.scrollToBottom()
    browser.list.viewport().grab()
    assert set(browser.delegate.icons) == in_view | rows_in_view(browser)  # the rows scrolled to
    browser.reject()


def test_a_swatch_shows_the_maps_colours_left_to_right():
    name = "Black-Body Radiation"
    image = swatch_image(name)
    assert (image.width(), image.height()) == (SWATCH.width(), SWATCH.height())
    stops = unit_stops(name)
    for column in (0, 30, 60, SWATCH.width() - 1):
        x = (column + 0.5) / SWATCH.width()
        expected = [round(255 * np.interp(x, stops[:, 0], stops[:, c])) for c in (1, 2, 3)]
        color = QColor(image.pixel(column, SWATCH.height() // 2))
        assert [color.red(), color.green(), color.blue()] == expected


# ---------------------------------------------------------------------------- zooming the value axis
def test_the_wheel_zooms_about_the_cursor_and_whole_range_resets(qtbot, editor, state):
    curve = editor.curve
    assert (curve.axis.lo, curve.axis.hi) == (0.0, 1.0) and not editor.zoom_all_button.isEnabled()
    pos = curve.position_of(0.3, 0.5)
    center = curve.value_at(pos.x())
    wheel(curve, pos)
    lo = center - center * ZOOM_STEP
    assert curve.axis.lo == pytest.approx(lo, abs=1e-12)
    assert curve.axis.hi == pytest.approx(lo + ZOOM_STEP, abs=1e-12)
    assert curve.value_at(pos.x()) == pytest.approx(center, abs=1e-12)  # the value under the cursor stays
    assert editor.color_bar.axis == curve.axis  # the colour bar lines up
    assert curve.view_labels() == (f"{curve.axis.lo:.5g}", f"{curve.axis.hi:.5g}")  # drawn at the plot's ends
    editor.grab()
    assert (curve.limits.lo, curve.limits.hi) == (0.0, 1.0)  # where points may go is unchanged
    wheel(editor.color_bar, editor.color_bar.position_of(0.3), 2)  # the bar zooms the same view
    assert curve.axis.hi - curve.axis.lo == pytest.approx(ZOOM_STEP**3)
    assert editor.zoom_all_button.isEnabled()
    wheel(curve, pos, -10)  # out past the whole range: the whole range
    assert (curve.axis.lo, curve.axis.hi) == (0.0, 1.0)
    wheel(curve, QPoint(curve.width() - MARGIN, 0), 3)  # about the end: it stays at the right edge
    assert curve.axis.hi == 1.0 and curve.axis.lo == pytest.approx(1.0 - ZOOM_STEP**3, abs=1e-12)
    wheel(curve, QPoint(MARGIN, 0), -1)  # out about the left edge: past the end, so slid back inside
    assert curve.axis.hi == 1.0 and curve.axis.lo == pytest.approx(1.0 - ZOOM_STEP**2, abs=1e-12)
    qtbot.mouseClick(editor.zoom_all_button, Qt.LeftButton)
    assert (curve.axis.lo, curve.axis.hi) == (0.0, 1.0) and not editor.zoom_all_button.isEnabled()
    assert curve.view_labels() is None


def test_zoom_to_the_tf_range_keeps_every_point_and_drags_land_under_the_mouse(qtbot, editor, state, history):
    tf = state.transfer_function
    tf.rescale(0.4, 0.6)  # inside the data range: the limits are the data's
    data_lo, data_hi = state.volume.value_range
    opacity, colors = tf.opacity_points, tf.color_points
    qtbot.mouseClick(editor.zoom_tf_button, Qt.LeftButton)
    curve = editor.curve
    assert (curve.axis.lo, curve.axis.hi) == (0.4, 0.6)
    assert (curve.limits.lo, curve.limits.hi) == (data_lo, data_hi)
    assert [p.x() for p in editor.stop_positions()][::4] == [MARGIN, editor.color_bar.width() - MARGIN]
    wheel(curve, curve.position_of(0.5, 0.5), 8)  # closer: only the peak at 0.5 stays in view
    view = curve.axis
    assert 0.48 < view.lo < 0.5 < view.hi < 0.52
    np.testing.assert_array_equal(tf.opacity_points, opacity)  # zooming moves no point
    np.testing.assert_array_equal(tf.color_points, colors)
    assert history.stack.count() == 1  # just the rescale
    index = 2  # the peak, at 0.5
    target = curve.position_of(view.lo + 0.3 * (view.hi - view.lo), 0.25)
    drag(qtbot, curve, editor.point_positions()[index], target)
    points = tf.opacity_points
    assert points[index, 0] == curve.value_at(target.x()) and points[index, 1] == curve.opacity_at(target.y())
    np.testing.assert_array_equal(np.delete(points, index, axis=0), np.delete(opacity, index, axis=0))
    assert curve.axis == view  # the view stays after the drag
    # a typed value goes where it is typed, outside the view too (between the neighbours)
    type_into(qtbot, editor.point_entry.value, f"{opacity[index - 1, 0] + 0.001:.6f}")
    assert tf.opacity_points[index, 0] == pytest.approx(opacity[index - 1, 0] + 0.001, abs=1e-9)
    assert tf.opacity_points[index, 0] < view.lo


def test_an_end_point_dragged_past_the_zoomed_view_stops_at_the_limits(qtbot, editor, state):
    editor.zoom_to(0.2, 0.8)
    curve = editor.curve
    tf = state.transfer_function
    drag(qtbot, curve, curve.position_of(0.5, tf.opacity_points[2, 1]), QPoint(-400, 0))
    assert tf.opacity_points[2, 0] == 0.4  # its neighbour
    editor.zoom_to(0.9, 1.0)
    drag(qtbot, curve, editor.point_positions()[-1], QPoint(curve.width() + 400, 0))
    assert tf.opacity_points[-1, 0] == 1.0  # the limits' end, not further


def test_the_zoomed_histogram_is_binned_over_the_view(qtbot, editor, state):
    volume = state.volume
    curve = editor.curve
    assert curve.histogram is value_histogram(volume)
    editor.zoom_to(0.25, 0.5)
    qtbot.waitUntil(lambda: curve.histogram is not value_histogram(volume), timeout=2000)
    counts, edges = np.histogram(volume.values, len(value_histogram(volume).counts), (0.25, 0.5))
    np.testing.assert_array_equal(curve.histogram.counts, counts)
    np.testing.assert_allclose(curve.histogram.edges, edges, rtol=0, atol=1e-15)
    editor.grab()  # paints the finer bars
    editor.reset_zoom()
    assert curve.histogram is value_histogram(volume)


def test_a_new_volume_shows_its_whole_range(qtbot, editor, state):
    editor.zoom_to(0.25, 0.5)
    values = np.linspace(-3.0, 5.0, 4**3).reshape(4, 4, 4)
    volume = UniformVolume(values)
    state.load(volume, default_transfer_function(volume), default_camera(volume))
    assert (editor.curve.axis.lo, editor.curve.axis.hi) == (-3.0, 5.0)
    assert editor.curve.histogram is value_histogram(volume)


# ---------------------------------------------------------------------------- 2D hover readout
@pytest.fixture
def editor_2d(qtbot) -> TransferFunction2DEditor:
    n = 17
    axis = np.linspace(-1.0, 1.0, n)
    z, y, x = np.meshgrid(axis, axis, axis, indexing="ij")
    volume = UniformVolume(np.sqrt(x * x + y * y + z * z), (2.0 / (n - 1),) * 3, (-1.0,) * 3)
    gaussian = TFWidget.gaussian((0.9, 1.0), (0.1, 0.2), (1.0, 0.5, 0.0), 0.6)
    s = ViewState()
    s.load(volume, TransferFunction2D((0.0, 1.8), (0.0, 2.0), [gaussian], 0.1), default_camera(volume))
    return shown(qtbot, TransferFunction2DEditor(s), (560, 440))


def test_the_hover_readout_shows_what_is_under_the_mouse(qtbot, editor_2d):
    canvas = editor_2d.canvas
    tf = editor_2d.transfer_function
    histogram = canvas.histogram
    assert histogram is joint_histogram(editor_2d._state.volume, gradient_max=2.0, value_range=(0.0, 1.8))
    assert canvas.hover_readout() is None
    plain = canvas.grab().toImage()
    # the fullest bin's middle: a count that means something
    j, i = np.unravel_index(np.argmax(histogram.counts), histogram.shape)
    n_gradients, n_values = histogram.shape
    pixel = canvas.to_pixel((i + 0.5) * 1.8 / n_values, (j + 0.5) * 2.0 / n_gradients)
    hover(canvas, pixel)
    readout = canvas.hover_readout()
    s, g = canvas.to_data(pixel)
    assert (readout.value, readout.gradient) == (s, g)
    assert int(s / 1.8 * n_values) == i and int(g / 2.0 * n_gradients) == j  # the bin of that pixel
    assert readout.count == histogram.counts[j, i] > 0
    assert readout.opacity == pytest.approx(float(tf.sample(s, g)[1]), abs=1e-15)
    assert readout.lines() == (
        f"value {s:.5g}  |grad| {g:.4g}",
        f"count {readout.count:.6g}  opacity {readout.opacity:.3f}",
    )
    # drawn in the plot's top-right corner, and gone when the mouse leaves
    plot = canvas.plot_rect()
    corner = QRect(round(plot.right()) - 100, round(plot.top()), 100, 30)
    assert canvas.grab().toImage().copy(corner) != plain.copy(corner)
    QApplication.sendEvent(canvas, QEvent(QEvent.Leave))
    assert canvas.hover_readout() is None
    assert canvas.grab().toImage().copy(corner) == plain.copy(corner)


def test_the_hover_readout_follows_the_tf_and_ignores_the_margins(qtbot, editor_2d):
    canvas = editor_2d.canvas
    tf = editor_2d.transfer_function
    pixel = canvas.widget_pixel(0)  # the Gaussian's centre
    hover(canvas, pixel)
    peak = canvas.hover_readout().opacity
    assert peak == pytest.approx(0.6, abs=0.01)
    tf.replace_widget(0, TFWidget.gaussian((0.9, 1.0), (0.1, 0.2), (1.0, 0.5, 0.0), 0.3))
    assert canvas.hover_readout().opacity == pytest.approx(peak / 2, abs=1e-9)
    hover(canvas, QPoint(2, canvas.height() - 2))  # the value labels' margin: no readout
    assert MARGINS[3] > 2 and canvas.hover_readout() is None
