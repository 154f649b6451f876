"""Rows the file dialogs (screenshot, movie) share: a path with a Browse button, a width x height
pair of boxes, clamped spin boxes, and running a dialog modally for its choice."""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

from PyQt5.QtWidgets import QDialog, QHBoxLayout, QLabel, QLineEdit, QPushButton, QSpinBox, QWidget

D = TypeVar("D", bound=QDialog)
T = TypeVar("T")


def path_row(parent: QWidget, path: str, browse: Callable[[], None]) -> tuple[QLineEdit, QHBoxLayout]:
    """A line edit holding `path` and a "Browse…" button calling `browse`, side by side."""
    edit = QLineEdit(path, parent)
    button = QPushButton("Browse…", parent)
    button.clicked.connect(browse)
    row = QHBoxLayout()
    row.addWidget(edit, 1)
    row.addWidget(button)
    return edit, row


def size_row(parent: QWidget, width_box: QSpinBox, height_box: QSpinBox) -> QHBoxLayout:
    """ "`width_box` x `height_box` pixels", in one row."""
    row = QHBoxLayout()
    row.addWidget(width_box)
    row.addWidget(QLabel("x", parent))
    row.addWidget(height_box)
    row.addWidget(QLabel("pixels", parent), 1)
    return row


def clamped_spin(parent: QWidget, lo: int, hi: int, value: int) -> QSpinBox:
    """A spin box over [lo, hi] starting at `value` clamped into that range."""
    box = QSpinBox(parent)
    box.setRange(lo, hi)
    box.setValue(max(lo, min(hi, int(value))))
    return box


def run_modal(dialog: D, choice: Callable[[D], T]) -> T | None:
    """`choice(dialog)` when the person accepts the modal `dialog`, None when they cancel; the
    dialog is deleted either way."""
    try:
        return choice(dialog) if dialog.exec_() == QDialog.Accepted else None
    finally:
        dialog.deleteLater()
