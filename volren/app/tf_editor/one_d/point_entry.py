"""Numeric entry of the selected opacity point: its value and its opacity, typed.

Why: dragging places a point to a pixel; a person matching a threshold from a paper or a
Hounsfield value needs the number itself (ParaView's and Slicer's editors have these fields).
The fields follow the opacity curve's selection and the TF's edits; an entry moves the point as a
drag would (between its neighbours, opacity in [0, 1]), as one undo step.
"""

from __future__ import annotations

import numpy as np
from PyQt5.QtWidgets import QDoubleSpinBox, QHBoxLayout, QLabel, QWidget

from volren.app.tf_editor.one_d.opacity_curve import OpacityCurve
from volren.app.tf_editor.one_d.point_canvas import neighbours
from volren.model.transfer_function import TransferFunction1D


class PointEntry(QWidget):
    """ "Point: value [ ] opacity [ ]" for the curve's selected point (disabled without one)."""

    def __init__(self, curve: OpacityCurve, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._curve = curve
        self._shown = (0.0, 0.0)  # (value, opacity) boxes as refresh() left them
        self.value = QDoubleSpinBox(self)
        self.value.setDecimals(6)
        self.value.setMinimumWidth(60)  # its hint fits the widest allowed value; the dock must fit ~300 px
        self.value.setToolTip("Data value of the selected opacity point (between its neighbours)")
        self.opacity = QDoubleSpinBox(self)
        self.opacity.setDecimals(3)
        self.opacity.setRange(0.0, 1.0)
        self.opacity.setSingleStep(0.01)
        self.opacity.setToolTip("Opacity of the selected point (per unit distance)")
        layout = QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(QLabel("Point", self))
        layout.addWidget(self.value, 2)
        layout.addWidget(QLabel("opacity", self))
        layout.addWidget(self.opacity, 1)
        self.value.editingFinished.connect(self._commit)
        self.opacity.editingFinished.connect(self._commit)
        curve.selectionChanged.connect(lambda _index: self.refresh())
        self.refresh()

    def _point(self) -> tuple[TransferFunction1D, int] | None:
        tf = self._curve.transfer_function()
        index = self._curve.selected
        if tf is None or index is None or index >= len(tf.opacity_points):
            return None
        return tf, index

    def refresh(self) -> None:
        """Show the selected point's numbers (the TF changed, or the selection)."""
        found = self._point()
        self.setEnabled(found is not None)
        if found is None:
            return
        tf, index = found
        points = tf.opacity_points
        x, a = points[index]
        left, right = neighbours(points[:, 0], index)
        limits = self._curve.limits
        # the range is where the point may go (between its neighbours): typing beyond stops there,
        # and the box is as wide as those numbers, not as the largest float
        self.value.blockSignals(True)
        self.value.setRange(left if left is not None else min(float(x), limits.lo),
                            right if right is not None else max(float(x), limits.hi))  # fmt: skip
        self.value.blockSignals(False)
        for box, v in ((self.value, x), (self.opacity, a)):
            box.blockSignals(True)
            box.setValue(float(v))
            box.blockSignals(False)
        # the numbers to the boxes' decimals: a box left as shown keeps the point's exact number
        self._shown = (self.value.value(), self.opacity.value())
        span = float(np.ptp(points[:, 0])) or 1.0
        self.value.setSingleStep(span / 100)

    def _commit(self) -> None:
        found = self._point()
        if found is None:
            return
        tf, index = found
        points = tf.opacity_points
        left, right = neighbours(points[:, 0], index)
        x, a = points[index]
        if self.value.value() != self._shown[0]:
            x = self._curve.limits.clamp(self.value.value(), left, right)
        if self.opacity.value() != self._shown[1]:
            a = min(max(self.opacity.value(), 0.0), 1.0)
        moved = (x, a)
        if moved != tuple(points[index]):
            points[index] = moved
            tf.set_opacity_points(points)  # one edit: one undo step and one full frame
        self.refresh()
