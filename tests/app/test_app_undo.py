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
