"""The colour bar of the 1D TF editor, and the value axis it shares with the opacity curve.

The bar shows the TF's colours along the value axis with a marker under each colour stop, as
ParaView's colour map editor does: click adds a stop (in the colour already shown there, so the
gradient does not change), drag moves it between its neighbours, double-click picks its colour,
right-click or Delete removes it. The first and last stops stay: they span the TF's colours, and
removing one would silently change the value range the range boxes and presets work on.

Edits go straight to the `ViewState`'s TF object; a drag is wrapped in begin/end_interaction so
the viewport previews it and the undo history records it as one step.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from PyQt5.QtCore import QPoint, QPointF, QRectF, QSize, Qt
from PyQt5.QtGui import (
    QColor,
    QHideEvent,
    QImage,
    QKeyEvent,
    QMouseEvent,
    QPainter,
    QPaintEvent,
    QPalette,
    QPolygonF,
)
from PyQt5.QtWidgets import QColorDialog, QSizePolicy, QWidget

from volren.app.state import ViewState
from volren.model.transfer_function import TransferFunction1D

#: Horizontal room at both ends of the axis (px): a marker or point at the end stays whole.
MARGIN = 8
#: How close (px) a click must be to a stop or point to pick it rather than add a new one.
PICK_RADIUS = 6


@dataclass(frozen=True)
class ValueAxis:
    """Data values <-> widget x, shared by the opacity curve and the colour bar so they line up."""

    lo: float
    hi: float

    @classmethod
    def spanning(cls, *ranges: tuple[float, float]) -> ValueAxis:
        """The union of `ranges`, widened when it is a single value (a constant volume or TF)."""
        lo = min(r[0] for r in ranges)
        hi = max(r[1] for r in ranges)
        if not hi > lo:
            pad = 0.5 * max(abs(lo), 1.0)
            lo, hi = lo - pad, hi + pad
        return cls(float(lo), float(hi))

    def to_x(self, value: Any, width: int) -> Any:
        """Widget x of `value` (a number or an array) in a widget `width` pixels wide."""
        return MARGIN + (value - self.lo) / (self.hi - self.lo) * _span(width)

    def to_value(self, x: Any, width: int) -> Any:
        """The data value at widget x (a number or an array)."""
        return self.lo + (x - MARGIN) / _span(width) * (self.hi - self.lo)

    def clamp(self, value: float, lo: float | None = None, hi: float | None = None) -> float:
        """`value` inside the axis and inside [lo, hi] where given (a point's neighbours)."""
        low = self.lo if lo is None else max(lo, self.lo)
        high = self.hi if hi is None else min(hi, self.hi)
        return float(min(max(value, low), max(low, high)))


def _span(width: int) -> float:
    return float(max(width - 2 * MARGIN, 1))


def color_strip(tf: TransferFunction1D, axis: ValueAxis, width: int) -> QImage:
    """A one-row image of the TF's colours, one column per widget pixel (sampled at its centre)."""
    width = max(width, 1)
    rgb, _ = tf.sample(axis.to_value(np.arange(width) + 0.5, width))
    pixels = np.ascontiguousarray(np.round(rgb * 255.0).astype(np.uint8).reshape(1, width, 3))
    return QImage(pixels.data, width, 1, 3 * width, QImage.Format_RGB888).copy()


def tf_color(tf: TransferFunction1D, value: float) -> QColor:
    """The TF's colour at `value`."""
    rgb, _ = tf.sample([value])
    return QColor.fromRgbF(*(float(c) for c in rgb[0]))


def neighbours(xs: np.ndarray, index: int) -> tuple[float | None, float | None]:
    """The x of the points left and right of `index` (None at the ends): a dragged point stays
    between them, so dragging never reorders points."""
    left = float(xs[index - 1]) if index > 0 else None
    right = float(xs[index + 1]) if index + 1 < len(xs) else None
    return left, right


class ColorBar(QWidget):
    """The TF's colours with a marker per colour stop; edits the state's 1D TF."""

    STRIP_HEIGHT = 16
    MARKER_HEIGHT = 9

    def __init__(self, state: ViewState, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._state = state
        self._axis = ValueAxis(0.0, 1.0)
        self._drag: int | None = None
        #: Index of the selected colour stop (Delete removes it), or None.
        self.selected: int | None = None
        self.setFocusPolicy(Qt.StrongFocus)
        self.setSizePolicy(QSizePolicy.Expanding, QSizePolicy.Fixed)
        self.setFixedHeight(2 + self.STRIP_HEIGHT + self.MARKER_HEIGHT + 3)
        self.setMinimumWidth(2 * MARGIN + 40)
        self.setToolTip(
            "Colour stops: click to add, drag to move, double-click to pick a colour, right-click or Delete to remove"
        )

    def sizeHint(self) -> QSize:
        return QSize(300, self.height())

    # ------------------------------------------------------------------ model access
    def transfer_function(self) -> TransferFunction1D | None:
        tf = self._state.transfer_function
        return tf if isinstance(tf, TransferFunction1D) else None

    @property
    def axis(self) -> ValueAxis:
        return self._axis

    def set_axis(self, axis: ValueAxis) -> None:
        self._axis = axis
        self.update()

    def model_changed(self) -> None:
        """The TF changed or was replaced: forget a selection that no longer exists."""
        tf = self.transfer_function()
        if tf is None or (self.selected is not None and self.selected >= len(tf.color_points)):
            self.selected = None
        self.update()

    # ------------------------------------------------------------------ geometry
    def _strip_rect(self) -> QRectF:
        return QRectF(MARGIN, 2, _span(self.width()), self.STRIP_HEIGHT)

    def value_at(self, x: float) -> float:
        return self._axis.to_value(x, self.width())

    def position_of(self, value: float) -> QPoint:
        """Where `value` is on the strip, in this widget's pixels."""
        return QPoint(round(self._axis.to_x(value, self.width())), 2 + self.STRIP_HEIGHT // 2)

    def stop_positions(self) -> list[QPoint]:
        """Widget-pixel centres of the stop markers, in stop order."""
        tf = self.transfer_function()
        if tf is None:
            return []
        y = 2 + self.STRIP_HEIGHT + self.MARKER_HEIGHT // 2
        return [QPoint(round(self._axis.to_x(x, self.width())), y) for x in tf.color_points[:, 0]]

    def _pick(self, x: float) -> int | None:
        """The stop nearest to `x` within PICK_RADIUS (the whole height counts: a bar is thin)."""
        tf = self.transfer_function()
        if tf is None:
            return None
        distance = np.abs(self._axis.to_x(tf.color_points[:, 0], self.width()) - x)
        best = int(np.argmin(distance))
        return best if distance[best] <= PICK_RADIUS else None

    # ------------------------------------------------------------------ edits
    def choose_color(self, initial: QColor) -> QColor | None:
        """Ask for a colour (a modal dialog); None when cancelled. Tests replace this method."""
        color = QColorDialog.getColor(initial, self, "Colour of the stop")
        return color if color.isValid() else None

    def add_stop(self, value: float) -> int:
        """Add a stop at `value` in the colour shown there; returns its index."""
        tf = self.transfer_function()
        assert tf is not None
        points = tf.color_points
        value = self._axis.clamp(value)
        color = tf_color(tf, value)
        index = int(np.searchsorted(points[:, 0], value, side="right"))
        row = [value, color.redF(), color.greenF(), color.blueF()]
        tf.set_color_points(np.insert(points, index, row, axis=0))
        return index

    def set_stop_color(self, index: int, color: QColor) -> None:
        tf = self.transfer_function()
        assert tf is not None
        points = tf.color_points
        points[index, 1:] = (color.redF(), color.greenF(), color.blueF())
        tf.set_color_points(points)

    def delete_selected(self) -> bool:
        """Remove the selected stop unless it is the first or the last; True if removed."""
        tf = self.transfer_function()
        if tf is None or self.selected is None:
            return False
        points = tf.color_points
        if not 0 < self.selected < len(points) - 1:
            return False
        index, self.selected = self.selected, None
        tf.set_color_points(np.delete(points, index, axis=0))
        return True

    def _move(self, index: int, x: float) -> None:
        tf = self.transfer_function()
        if tf is None or index >= len(tf.color_points):
            return
        points = tf.color_points
        left, right = neighbours(points[:, 0], index)
        value = self._axis.clamp(self.value_at(x), left, right)
        if value != points[index, 0]:
            points[index, 0] = value
            tf.set_color_points(points)

    # ------------------------------------------------------------------ mouse and keys
    def mousePressEvent(self, event: QMouseEvent) -> None:
        if self.transfer_function() is None:
            return
        x = event.localPos().x()
        hit = self._pick(x)
        if event.button() == Qt.RightButton:
            if hit is not None:
                self.selected = hit
                self.delete_selected()
            return
        if event.button() != Qt.LeftButton:
            return
        self._state.begin_interaction()
        self._drag = hit if hit is not None else self.add_stop(self.value_at(x))
        self.selected = self._drag
        self.update()

    def mouseMoveEvent(self, event: QMouseEvent) -> None:
        if self._drag is not None:
            self._move(self._drag, event.localPos().x())

    def mouseReleaseEvent(self, event: QMouseEvent) -> None:
        if event.button() == Qt.LeftButton:
            self._end_drag()

    def _end_drag(self) -> None:
        if self._drag is not None:
            self._drag = None
            self._state.end_interaction()

    def mouseDoubleClickEvent(self, event: QMouseEvent) -> None:
        if event.button() != Qt.LeftButton or self.transfer_function() is None:
            return
        self._end_drag()
        hit = self._pick(event.localPos().x())
        if hit is None:
            return
        self.selected = hit
        tf = self.transfer_function()
        assert tf is not None
        r, g, b = tf.color_points[hit, 1:]
        color = self.choose_color(QColor.fromRgbF(float(r), float(g), float(b)))
        if color is not None and self.transfer_function() is tf and hit < len(tf.color_points):
            self.set_stop_color(hit, color)

    def keyPressEvent(self, event: QKeyEvent) -> None:
        if event.key() in (Qt.Key_Delete, Qt.Key_Backspace) and self.delete_selected():
            return
        super().keyPressEvent(event)

    def hideEvent(self, event: QHideEvent) -> None:
        self._end_drag()  # a drag cut short must not leave the state "interacting"
        super().hideEvent(event)

    # ------------------------------------------------------------------ painting
    def paintEvent(self, event: QPaintEvent) -> None:
        painter = QPainter(self)
        painter.fillRect(self.rect(), self.palette().color(QPalette.Window))
        tf = self.transfer_function()
        if tf is None:
            return
        strip = self._strip_rect()
        image = color_strip(tf, self._axis, self.width())
        painter.drawImage(strip, image, QRectF(strip.left(), 0, strip.width(), 1))
        painter.setPen(self.palette().color(QPalette.Mid))
        painter.drawRect(strip)
        painter.setRenderHint(QPainter.Antialiasing)
        top = strip.bottom() + 1
        half = self.MARKER_HEIGHT * 0.6
        for index, (x, r, g, b) in enumerate(tf.color_points):
            px = self._axis.to_x(x, self.width())
            marker = QPolygonF(
                [
                    QPointF(px, top),
                    QPointF(px - half, top + self.MARKER_HEIGHT),
                    QPointF(px + half, top + self.MARKER_HEIGHT),
                ]
            )
            chosen = index == self.selected
            pen = self.palette().color(QPalette.Highlight if chosen else QPalette.Text)
            painter.setPen(pen)
            painter.setBrush(QColor.fromRgbF(float(r), float(g), float(b)))
            painter.drawPolygon(marker)
            if chosen:
                painter.drawLine(QPointF(px, strip.top()), QPointF(px, strip.bottom()))
