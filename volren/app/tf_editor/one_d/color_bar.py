"""The colour bar of the 1D TF editor: the TF's colours along the value axis, with its stops.

The bar shows the TF's colours along the value axis with a marker under each colour stop, as
ParaView's colour map editor does: click adds a stop (in the colour already shown there, so the
gradient does not change), drag moves it between its neighbours, double-click picks its colour,
right-click or Delete removes it. The first and last stops stay: they span the TF's colours, and
removing one would silently change the value range the range boxes and presets work on.

Edits go straight to the `ViewState`'s TF object; a drag is wrapped in begin/end_interaction so
the viewport previews it and the undo history records it as one step.
"""

from __future__ import annotations

from collections import OrderedDict

import numpy as np
from PyQt5.QtCore import QPoint, QPointF, QRectF, QSize, Qt
from PyQt5.QtGui import (
    QColor,
    QImage,
    QMouseEvent,
    QPainter,
    QPaintEvent,
    QPalette,
    QPolygonF,
)
from PyQt5.QtWidgets import QColorDialog, QSizePolicy, QWidget

from volren.app.core.state import ViewState
from volren.app.tf_editor.one_d.point_canvas import (
    MARGIN,
    PICK_RADIUS,
    PointCanvas,
    ValueAxis,
    axis_span,
    neighbours,
)
from volren.model.transfer_function import TransferFunction1D

#: Colour strips kept, newest last: the opacity curve and the colour bar draw the same TF version
#: at their widths, each repaint of a TF drag (the strip was most of a repaint's time).
_STRIPS: OrderedDict[tuple, QImage] = OrderedDict()
STRIPS_KEPT = 4


def color_strip(tf: TransferFunction1D, axis: ValueAxis, width: int) -> QImage:
    """A one-row image of the TF's colours, one column per widget pixel (sampled at its centre)."""
    width = max(width, 1)
    key = (id(tf), tf.version, axis, width)
    image = _STRIPS.get(key)
    if image is None:
        rgb, _ = tf.sample(axis.to_value(np.arange(width) + 0.5, width))
        pixels = np.ascontiguousarray(np.round(rgb * 255.0).astype(np.uint8).reshape(1, width, 3))
        image = QImage(pixels.data, width, 1, 3 * width, QImage.Format_RGB888).copy()
        _STRIPS[key] = image
        while len(_STRIPS) > STRIPS_KEPT:
            _STRIPS.popitem(last=False)
    return image


def tf_color(tf: TransferFunction1D, value: float) -> QColor:
    """The TF's colour at `value`."""
    rgb, _ = tf.sample([value])
    return QColor.fromRgbF(*(float(c) for c in rgb[0]))


class ColorBar(PointCanvas):
    """The TF's colours with a marker per colour stop; edits the state's 1D TF."""

    STRIP_HEIGHT = 16
    MARKER_HEIGHT = 9

    def __init__(self, state: ViewState, parent: QWidget | None = None) -> None:
        super().__init__(state, parent)
        self.setSizePolicy(QSizePolicy.Expanding, QSizePolicy.Fixed)
        self.setFixedHeight(2 + self.STRIP_HEIGHT + self.MARKER_HEIGHT + 3)
        self.setMinimumWidth(2 * MARGIN + 40)
        self.setToolTip(
            "Colour stops: click to add, drag to move, double-click to pick a colour, right-click or Delete to remove; "
            "wheel: zoom"
        )

    def sizeHint(self) -> QSize:
        return QSize(300, self.height())

    # ------------------------------------------------------------------ the points edited
    def _points(self, tf: TransferFunction1D) -> np.ndarray:
        return tf.color_points

    def _set_points(self, tf: TransferFunction1D, points: np.ndarray) -> None:
        tf.set_color_points(points)

    # ------------------------------------------------------------------ geometry
    def _strip_rect(self) -> QRectF:
        return QRectF(MARGIN, 2, axis_span(self.width()), self.STRIP_HEIGHT)

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

    def _pick(self, pos: QPointF) -> int | None:
        """The stop nearest to `pos` within PICK_RADIUS in x (the whole height counts: a bar is thin)."""
        tf = self.transfer_function()
        if tf is None:
            return None
        distance = np.abs(self._axis.to_x(tf.color_points[:, 0], self.width()) - pos.x())
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
        value = self._limits.clamp(value)
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

    def _add_at(self, pos: QPointF) -> int:
        return self.add_stop(self.value_at(pos.x()))

    def _move(self, index: int, pos: QPointF) -> None:
        tf = self.transfer_function()
        if tf is None or index >= len(tf.color_points):
            return
        points = tf.color_points
        left, right = neighbours(points[:, 0], index)
        value = self._limits.clamp(self.value_at(pos.x()), left, right)
        if value != points[index, 0]:
            points[index, 0] = value
            tf.set_color_points(points)

    # ------------------------------------------------------------------ mouse and keys
    def mouseDoubleClickEvent(self, event: QMouseEvent) -> None:
        if event.button() != Qt.LeftButton or self.transfer_function() is None:
            return
        self._end_drag()
        hit = self._pick(event.localPos())
        if hit is None:
            return
        self.selected = hit
        tf = self.transfer_function()
        assert tf is not None
        r, g, b = tf.color_points[hit, 1:]
        color = self.choose_color(QColor.fromRgbF(float(r), float(g), float(b)))
        if color is not None and self.transfer_function() is tf and hit < len(tf.color_points):
            self.set_stop_color(hit, color)

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
