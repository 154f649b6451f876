"""Numeric entry of the selected colour stop: its value typed, its colour picked.

Why: dragging a stop places it to a pixel; matching a colour map to known thresholds (a tissue's
Hounsfield range, a contour value) needs the number, and a colour needs its exact RGB (ParaView's
colour map editor has both). The fields follow the colour bar's selection and the TF's edits; a
typed value moves the stop as a drag would (between its neighbours, inside the editor's limits),
a picked colour recolours it, each as one edit, hence one undo step. Refreshing never writes back
(the spin box's signals are blocked meanwhile).
"""

from __future__ import annotations

import numpy as np
from PyQt5.QtGui import QColor
from PyQt5.QtWidgets import QDoubleSpinBox, QHBoxLayout, QLabel, QPushButton, QWidget

from volren.app.tf_editor.one_d.color_bar import ColorBar
from volren.app.tf_editor.one_d.point_canvas import neighbours
from volren.model.transfer_function import TransferFunction1D


def stop_color(points: np.ndarray, index: int) -> QColor:
    """The colour of stop `index` of colour points `points`."""
    r, g, b = (float(c) for c in points[index, 1:])
    return QColor.fromRgbF(r, g, b)


class ColorEntry(QWidget):
    """The row "Stop: value [ ] colour [■]" for the colour bar's selected stop (disabled without one)."""

    def __init__(self, bar: ColorBar, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._bar = bar
        self._shown = 0.0  # the value box as refresh() left it
        self.value = QDoubleSpinBox(self)
        self.value.setDecimals(6)
        self.value.setMinimumWidth(60)  # its hint fits the widest allowed value; the dock must fit ~300 px
        self.value.setToolTip("Data value of the selected colour stop (between its neighbours)")
        self.color_button = QPushButton(self)
        self.color_button.setToolTip("Colour of the selected stop: click to pick it (RGB, HSV or #hex)")
        self.color_button.setMinimumWidth(72)
        layout = QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(QLabel("Stop", self))
        layout.addWidget(self.value, 2)
        layout.addWidget(QLabel("colour", self))
        layout.addWidget(self.color_button, 1)
        self.value.editingFinished.connect(self._commit_value)
        self.color_button.clicked.connect(self.pick_color)
        bar.selectionChanged.connect(lambda _index: self.refresh())
        self.refresh()

    def _stop(self) -> tuple[TransferFunction1D, int] | None:
        tf = self._bar.transfer_function()
        index = self._bar.selected
        if tf is None or index is None or index >= len(tf.color_points):
            return None
        return tf, index

    def refresh(self) -> None:
        """Show the selected stop's value and colour (the TF changed, or the selection)."""
        found = self._stop()
        self.setEnabled(found is not None)
        if found is None:
            self.color_button.setText("")
            self.color_button.setStyleSheet("")
            return
        tf, index = found
        points = tf.color_points
        x = float(points[index, 0])
        left, right = neighbours(points[:, 0], index)
        limits = self._bar.limits
        self.value.blockSignals(True)
        # where the stop may go (between its neighbours): typing beyond stops there
        self.value.setRange(left if left is not None else min(x, limits.lo),
                            right if right is not None else max(x, limits.hi))  # fmt: skip
        self.value.setSingleStep((float(np.ptp(points[:, 0])) or 1.0) / 100)
        self.value.setValue(x)
        self.value.blockSignals(False)
        self._shown = self.value.value()  # x to the box's decimals: leaving the box unchanged keeps x
        color = stop_color(points, index)
        text = "#000" if color.lightnessF() > 0.5 else "#fff"
        self.color_button.setText(color.name())
        self.color_button.setStyleSheet(f"background-color: {color.name()}; color: {text};")

    def _commit_value(self) -> None:
        found = self._stop()
        if found is None:
            return
        tf, index = found
        points = tf.color_points
        if self.value.value() == self._shown:
            return  # not typed in (focus left the box): the rounded number must not move the stop
        left, right = neighbours(points[:, 0], index)
        value = self._bar.limits.clamp(self.value.value(), left, right)
        if value != points[index, 0]:
            points[index, 0] = value
            tf.set_color_points(points)  # one edit: one undo step
        self.refresh()

    def set_color(self, color: QColor) -> None:
        """Recolour the selected stop (one edit); nothing when no stop is selected."""
        found = self._stop()
        if found is not None and color.isValid():
            self._bar.set_stop_color(found[1], color)
        self.refresh()

    def pick_color(self) -> None:
        """Ask for the selected stop's colour (the colour bar's dialog); cancel changes nothing."""
        found = self._stop()
        if found is None:
            return
        tf, index = found
        color = self._bar.choose_color(stop_color(tf.color_points, index))
        now = self._stop()  # the dialog is modal, but the TF may have been replaced meanwhile
        if color is not None and now is not None and now[0] is tf and now[1] == index:
            self.set_color(color)
