"""The Save Screenshot dialog: where to, at what size, or the whole window as shown.

`ask_screenshot` is looked up on this module at call time, so tests (and headless runs) can
replace the modal dialog.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from PyQt5.QtWidgets import (
    QCheckBox,
    QDialog,
    QDialogButtonBox,
    QFileDialog,
    QFormLayout,
    QSpinBox,
    QWidget,
)

from volren.app.files.dialog_fields import clamped_spin, path_row, run_modal, size_row
from volren.renderers.base import MAX_IMAGE_SIDE

PNG_FILTER = "PNG images (*.png)"


@dataclass(frozen=True)
class ScreenshotChoice:
    """What the screenshot dialog asked for: a PNG path and a size, or the whole window as shown."""

    path: str
    width: int
    height: int
    whole_window: bool = False


def png_path(path: str) -> str:
    """`path`, with ".png" added when it has another suffix or none (what the file will hold)."""
    return path if Path(path).suffix.lower() == ".png" else path + ".png"


class ScreenshotDialog(QDialog):
    """File and resolution of a screenshot: width x height (default: the viewport's pixels), with
    the aspect ratio kept while editing if asked, or "whole window" for a grab of the window."""

    def __init__(self, parent: QWidget | None, path: str, size: tuple[int, int]) -> None:
        super().__init__(parent)
        self.setWindowTitle("Save screenshot")
        self._aspect = size[0] / size[1] if size[0] > 0 and size[1] > 0 else 1.0
        self._syncing = False

        self.path_edit, file_row = path_row(self, path, self._browse)
        self.width_box, self.height_box = (clamped_spin(self, 1, MAX_IMAGE_SIDE, v) for v in size)
        self.keep_aspect = QCheckBox("Keep the viewport's aspect ratio", self)
        self.keep_aspect.setChecked(True)
        self.whole_window = QCheckBox("Whole window, as shown (window size)", self)
        self.whole_window.toggled.connect(self._whole_window_toggled)
        self.width_box.valueChanged.connect(lambda v: self._side_changed(self.height_box, v / self._aspect))
        self.height_box.valueChanged.connect(lambda v: self._side_changed(self.width_box, v * self._aspect))

        self.buttons = QDialogButtonBox(QDialogButtonBox.Save | QDialogButtonBox.Cancel, self)
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        self.path_edit.textChanged.connect(
            lambda text: self.buttons.button(QDialogButtonBox.Save).setEnabled(bool(text.strip()))
        )

        form = QFormLayout(self)
        form.addRow("File:", file_row)
        form.addRow("Size:", size_row(self, self.width_box, self.height_box))
        form.addRow("", self.keep_aspect)
        form.addRow("", self.whole_window)
        form.addRow(self.buttons)

    def _side_changed(self, other: QSpinBox, value: float) -> None:
        if self._syncing or not self.keep_aspect.isChecked():
            return
        self._syncing = True
        try:
            other.setValue(max(1, min(MAX_IMAGE_SIDE, round(value))))
        finally:
            self._syncing = False

    def _whole_window_toggled(self, on: bool) -> None:
        for widget in (self.width_box, self.height_box, self.keep_aspect):
            widget.setEnabled(not on)

    def _browse(self) -> None:
        path, _ = QFileDialog.getSaveFileName(self, "Save screenshot", self.path_edit.text(), PNG_FILTER)
        if path:
            self.path_edit.setText(png_path(path))

    def choice(self) -> ScreenshotChoice:
        return ScreenshotChoice(
            png_path(self.path_edit.text().strip()),
            self.width_box.value(),
            self.height_box.value(),
            self.whole_window.isChecked(),
        )


def ask_screenshot(parent: QWidget | None, path: str, size: tuple[int, int]) -> ScreenshotChoice | None:
    """Run the screenshot dialog; None when cancelled. Looked up at call time so tests can patch it."""
    return run_modal(ScreenshotDialog(parent, path, size), ScreenshotDialog.choice)
