"""Picking a label in the view (Ctrl+click) and editing the selected label's own TF (Real-Time
Volume Graphics, chapter 16: a TF per object), with real widgets.

The scene of `test_label_picking`: a 33^3 grid of value 1, label 1 a slab |z - 16| <= 5, a ball of
label 3 (radius 5) inside it, label 0 hidden; seen along -z with a parallel camera. The oracle of a
frame is the raycast renderer given the TF per label the test expects, at the frame's own settings
and camera, converted to pixels as the render service converts them.
"""

from __future__ import annotations

import numpy as np
import pytest
from PyQt5.QtCore import QPoint, Qt

from tests.app.conftest import FRAME_TIMEOUT_MS
from volren.app.core.label_picking import pick_label
from volren.app.core.loading import LoadedInput
from volren.app.rendering.render_service import tf_key
from volren.io.image_io import to_png_pixels
from volren.model.camera import Camera
from volren.model.labels import LabelMap, LabelStyle, LabelTransferFunction
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import UniformVolume
from volren.renderers.base import render_frame
from volren.renderers.registry import registry

N, C, R = 33, 16, 5
FIRST_FRAME_TIMEOUT_MS = 180_000


def _volume() -> UniformVolume:
    k, j, i = np.mgrid[0:N, 0:N, 0:N]
    labels = np.zeros((N, N, N), np.uint8)
    labels[(abs(k - C) <= R) & (i >= 4) & (i <= 28) & (j >= 4) & (j <= 28)] = 1
    labels[(i - C) ** 2 + (j - C) ** 2 + (k - C) ** 2 <= R * R] = 3
    return UniformVolume(np.ones((N, N, N), np.float32), name="ball", labels=LabelMap(labels))


def _tf() -> TransferFunction1D:
    return TransferFunction1D(np.array([[0.0, 1, 1, 1], [1.0, 1, 1, 1]]), np.array([[0.0, 0.0], [1.0, 0.3]]))


def _current(window):
    def check(frame) -> bool:
        return (
            frame.tf_key == tf_key(window.state.drawn_transfer_function)
            and frame.renderer == window.state.renderer
        )

    return check


def _frame_after(window, qtbot, action, timeout_ms: int = FRAME_TIMEOUT_MS):
    with qtbot.waitSignal(window.fullFrameShown, timeout=timeout_ms, check_params_cb=_current(window)) as got:
        action()
    return got.args[0]


def _expected(window, frame, label_tf: LabelTransferFunction) -> np.ndarray:
    with registry.create(frame.renderer) as renderer:
        renderer.set_settings(frame.settings)
        renderer.set_volume(window.state.volume)
        renderer.set_transfer_function(label_tf)
        image, _ = render_frame(renderer, frame.camera, frame.width, frame.height)
    return to_png_pixels(image, window.state.background)


@pytest.fixture
def shown(make_window, qtbot, error_boxes):
    """A window showing the labelled ball with raycast along -z (parallel), label 0 hidden."""
    window = make_window()
    window.resize(700, 360)
    # previews by raycast too: these tests are about what is drawn, and another renderer's set-up
    # (a numba compilation on a cold cache) would hold the render thread for minutes
    window.scheduler._failed_previewers.update(n for n in registry.names() if n != "raycast")
    volume = _volume()
    loaded = LoadedInput(volume, _tf(), source="ball")
    _frame_after(window, qtbot, lambda: window.files.apply_loaded(loaded, "raycast"), FIRST_FRAME_TIMEOUT_MS)
    camera = Camera.orbit(volume.bounds, 0.0, 0.0, 1.0, True, window.viewport.aspect())
    _frame_after(window, qtbot, lambda: window.state.set_camera(camera))
    frame = _frame_after(window, qtbot, lambda: window.docks.labels.show_box(0).setChecked(False))
    assert error_boxes == [] and window.state.labels_drawn
    return window, frame


def _pixel_at(window, world_x: float, world_y: float) -> tuple[int, int]:
    """The viewport pixel whose ray passes nearest to (world_x, world_y) (seen along -z)."""
    width, height = window.viewport.pixel_size()
    origins, _ = window.state.camera.pixel_rays(width, height)
    distance = np.hypot(origins[..., 0] - world_x, origins[..., 1] - world_y)
    y, x = np.unravel_index(np.argmin(distance), distance.shape)
    return int(x), int(y)


def _ctrl_click(window, qtbot, pixel: tuple[int, int]) -> None:
    assert window.viewport.devicePixelRatioF() == 1.0  # a pixel is a point of the widget
    qtbot.mouseClick(window.viewport, Qt.LeftButton, Qt.ControlModifier, QPoint(*pixel))


def test_a_ctrl_click_selects_the_label_seen_there(shown, qtbot):
    window, _ = shown
    panel = window.docks.labels
    centre, beside, outside = (
        _pixel_at(window, C, C),
        _pixel_at(window, C + 8, C),
        _pixel_at(window, C + 14, C),
    )
    width, height = window.viewport.pixel_size()
    state = window.state
    for pixel in (centre, beside, outside):  # the view picks what the Qt-free picker picks
        hit = pick_label(
            state.render_volume, state.label_transfer_function, state.camera, *pixel, width, height
        )
        assert (hit.label if hit else None) == {centre: 3, beside: 1, outside: None}[pixel]
    _ctrl_click(window, qtbot, centre)
    assert panel.selected_label() == 3 and state.edited_label == 3
    assert "label 3" in window.statusBar().currentMessage()
    _ctrl_click(window, qtbot, beside)
    assert panel.selected_label() == 1 and state.edited_label == 1
    _ctrl_click(window, qtbot, outside)
    assert panel.selected_label() == 1 and "No label" in window.statusBar().currentMessage()


def test_a_plain_click_picks_nothing(shown, qtbot):
    window, _ = shown
    qtbot.mouseClick(window.viewport, Qt.LeftButton, Qt.NoModifier, QPoint(*_pixel_at(window, C, C)))
    assert window.docks.labels.selected_label() is None and window.state.edited_label is None


def test_editing_an_unstyled_label_gives_it_its_own_tf_from_the_base_undoably(shown, qtbot):
    window, before = shown
    state, panel, editor = window.state, window.docks.labels, window.docks.tf_panel.editor_1d
    stack = window.docks.history.stack
    base = state.base_transfer_function
    steps = stack.count()
    panel.select_label(3)
    assert state.edited_label == 3 and state.label_transfer_function.style(3).tf is None  # not yet its own
    edited = editor.transfer_function()
    assert edited is not base and edited == base  # a copy of the base
    assert stack.count() == steps  # a selection is not an edit
    frame = _frame_after(window, qtbot, lambda: editor.unit_spin.setValue(8.0))
    label_tf = state.label_transfer_function
    own = label_tf.style(3).tf
    assert own is edited and own.opacity_unit_distance == pytest.approx(8.0)
    assert base.opacity_unit_distance == 1.0 and label_tf.style(1).tf is None  # the others as they were
    assert stack.count() == steps + 1
    expected_tf = _tf()
    expected_tf.set_opacity_unit_distance(8.0)
    expected = LabelTransferFunction(_tf(), {0: LabelStyle(visible=False), 1: label_tf.style(1),
                                             3: LabelStyle(color=label_tf.style(3).color, tf=expected_tf)})  # fmt: skip
    np.testing.assert_array_equal(frame.rgb, _expected(window, frame, expected))
    assert not np.array_equal(frame.rgb, before.rgb)
    # a second edit edits the label's own TF in place: one more step, drawn at once
    second = _frame_after(window, qtbot, lambda: editor.unit_spin.setValue(2.0))
    assert state.label_transfer_function.style(3).tf.opacity_unit_distance == pytest.approx(2.0)
    assert stack.count() == steps + 2
    expected_tf.set_opacity_unit_distance(2.0)
    np.testing.assert_array_equal(second.rgb, _expected(window, second, expected))
    _frame_after(window, qtbot, window.docks.undo_action.trigger)
    frame = _frame_after(window, qtbot, window.docks.undo_action.trigger)
    assert state.label_transfer_function.style(3).tf is None and state.edited_label == 3
    assert editor.transfer_function() == state.base_transfer_function
    np.testing.assert_array_equal(frame.rgb, before.rgb)
    frame = _frame_after(window, qtbot, window.docks.redo_action.trigger)
    assert state.label_transfer_function.style(3).tf.opacity_unit_distance == pytest.approx(8.0)
    assert editor.transfer_function() is state.label_transfer_function.style(3).tf


def test_a_label_with_its_own_tf_is_edited_in_it_and_edit_base_goes_back(shown, qtbot):
    window, _ = shown
    state, panel, editor = window.state, window.docks.labels, window.docks.tf_panel.editor_1d
    own = _tf()
    own.set_opacity_unit_distance(5.0)
    label_tf = state.label_transfer_function
    _frame_after(window, qtbot, lambda: label_tf.set_style(1, LabelStyle(tf=own)))
    panel.select_label(1)
    assert editor.transfer_function() is own and panel.base_button.isEnabled()
    _frame_after(window, qtbot, lambda: editor.unit_spin.setValue(6.0))
    assert (
        own.opacity_unit_distance == pytest.approx(6.0)
        and state.base_transfer_function.opacity_unit_distance == 1.0
    )
    panel.base_button.click()
    assert state.edited_label is None and panel.selected_label() is None
    assert editor.transfer_function() is state.base_transfer_function
    frame = _frame_after(window, qtbot, lambda: editor.unit_spin.setValue(3.0))
    assert state.base_transfer_function.opacity_unit_distance == pytest.approx(3.0)
    assert own.opacity_unit_distance == pytest.approx(6.0)
    np.testing.assert_array_equal(frame.rgb, _expected(window, frame, state.label_transfer_function.copy()))
