"""Undo and redo as the person meets them: the Edit menu's labels, and the shortcuts in the
editors' number fields (pytest-qt, offscreen, a real window)."""

from __future__ import annotations

import pytest
from PyQt5.QtCore import Qt
from PyQt5.QtGui import QColor
from PyQt5.QtWidgets import QLabel

from tests.app.conftest import FRAME_TIMEOUT_MS

pytestmark = pytest.mark.qt


@pytest.fixture
def shown(make_window, ini, fake_renderers, sample, qtbot):
    """A window showing the sample with the constant-colour fake renderer."""
    w = make_window(settings=ini)
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.files.apply_loaded(sample, "fake")
    return w


def test_undo_labels_say_colour_as_the_editor_does(shown, qtbot):
    editor = shown.docks.tf_panel.editor_1d
    bar, entry = editor.color_bar, editor.color_entry
    qtbot.mouseClick(bar, Qt.LeftButton, pos=bar.stop_positions()[0])
    assert entry.isEnabled() and "colour" in [label.text() for label in entry.findChildren(QLabel)]
    entry.set_color(QColor(255, 0, 0))
    assert shown.docks.undo_action.text() == "&Undo edit colour"
    shown.docks.undo_action.trigger()
    assert shown.docks.redo_action.text() == "&Redo edit colour"


def test_the_undo_keys_in_a_number_field_undo_the_app_once_the_value_is_entered(shown, qtbot):
    """With the focus in a number field, Ctrl+Z undoes the value entered there (and Ctrl+Shift+Z
    or Ctrl+Y redoes it); typing not yet entered is the field's own to undo."""
    from PyQt5.QtWidgets import QApplication

    editor = shown.docks.tf_panel.editor_1d
    curve, box, stack = editor.curve, editor.point_entry.opacity, shown.docks.history.stack
    index = len(shown.state.transfer_function.opacity_points) // 2
    before = float(shown.state.transfer_function.opacity_points[index, 1])
    QApplication.setActiveWindow(shown)

    def opacity() -> float:
        return float(shown.state.transfer_function.opacity_points[index, 1])

    def focus_the_point() -> None:  # an undo replaces the TF, which clears the selection
        qtbot.mouseClick(curve, Qt.LeftButton, pos=curve.point_positions()[index])
        box.setFocus()
        qtbot.waitUntil(box.hasFocus)

    focus_the_point()
    box.selectAll()
    qtbot.keyClicks(box, "0.420")
    qtbot.keyClick(box, Qt.Key_Return)
    assert opacity() == 0.42 and stack.index() == 1 and box.hasFocus()
    for key, modifiers, expected in ((Qt.Key_Z, Qt.ControlModifier, before),
                                     (Qt.Key_Z, Qt.ControlModifier | Qt.ShiftModifier, 0.42),
                                     (Qt.Key_Z, Qt.ControlModifier, before),
                                     (Qt.Key_Y, Qt.ControlModifier, 0.42)):  # fmt: skip
        qtbot.keyClick(box, key, modifiers)
        assert opacity() == expected, (key, modifiers)
        focus_the_point()
    box.selectAll()
    qtbot.keyClicks(box, "0.1")  # not entered: Ctrl+Z takes back the typing, not the app's edit
    qtbot.keyClick(box, Qt.Key_Z, Qt.ControlModifier)
    assert box.text() == "0.420" and opacity() == 0.42 and stack.index() == 1
