"""The opacity canvas of the 1D TF editor: the data histogram behind the opacity curve.

As in ParaView's colour map editor, the area under the curve is filled with the TF's colours, so
one picture shows what each value looks like; the histogram behind says where the data is. Click
on empty space adds a point there, drag moves a point (between its neighbours, opacity in [0, 1]),
right-click or Delete removes one. The end points stay, like ParaView's: they bound the curve
and the TF's value range.

Edits go straight to the `ViewState`'s TF object; a click-and-drag is wrapped in
begin/end_interaction, so it previews cheaply and is one undo step.
"""

from __future__ import annotations

import numpy as np
from PyQt5.QtCore import QPoint, QPointF, QRectF, QSize, Qt
from PyQt5.QtGui import (
    QColor,
    QPainter,
    QPainterPath,
    QPaintEvent,
    QPalette,
    QPen,
    QPixmap,
    QPolygonF,
)
from PyQt5.QtWidgets import QSizePolicy, QWidget

from volren.app.core.state import ViewState
from volren.app.tf_editor.one_d.color_bar import color_strip
from volren.app.tf_editor.one_d.point_canvas import MARGIN, PICK_RADIUS, PointCanvas, neighbours
from volren.model.transfer_function import TransferFunction1D
from volren.model.value_histogram import Histogram

#: Vertical room above opacity 1 and below 0 (px), for the point markers and the readout.
TOP, BOTTOM = 8, 6
#: Alpha of the colour fill under the curve: the histogram stays readable through it.
FILL_OPACITY = 0.55


class OpacityCurve(PointCanvas):
    """The opacity points of the state's 1D TF over the value axis, with the histogram behind."""

    def __init__(self, state: ViewState, parent: QWidget | None = None) -> None:
        super().__init__(state, parent)
        self._histogram: Histogram | None = None
        self._histogram_layer: tuple[tuple, QPixmap] | None = None  # (what it shows, the bars drawn)
        # log by default: on CT and MR one value (air, background) holds 80-97 % of the voxels,
        # and linear counts drew an empty box
        self._log_counts = True
        self.setSizePolicy(QSizePolicy.Expanding, QSizePolicy.Expanding)
        self.setMinimumSize(2 * MARGIN + 40, TOP + BOTTOM + 40)
        self.setToolTip(
            "Opacity: click to add a point, drag to move it, right-click or Delete to remove it; wheel: zoom"
        )

    def sizeHint(self) -> QSize:
        return QSize(300, 150)

    # ------------------------------------------------------------------ the points edited
    def _points(self, tf: TransferFunction1D) -> np.ndarray:
        return tf.opacity_points

    def _set_points(self, tf: TransferFunction1D, points: np.ndarray) -> None:
        tf.set_opacity_points(points)

    @property
    def histogram(self) -> Histogram | None:
        return self._histogram

    def set_histogram(self, histogram: Histogram | None) -> None:
        self._histogram = histogram
        self.update()

    @property
    def log_counts(self) -> bool:
        return self._log_counts

    def set_log_counts(self, log: bool) -> None:
        self._log_counts = bool(log)
        self.update()

    # ------------------------------------------------------------------ geometry
    def view_labels(self) -> tuple[str, str] | None:
        """The values at the plot's two ends while the view is zoomed in (else None): without
        them a zoomed curve does not say where it is."""
        if self._axis == self._limits:
            return None
        return f"{self._axis.lo:.5g}", f"{self._axis.hi:.5g}"

    def _plot_height(self) -> float:
        return float(max(self.height() - TOP - BOTTOM, 1))

    def opacity_at(self, y: float) -> float:
        """The opacity at widget y, clamped to [0, 1]."""
        return float(min(max((self.height() - BOTTOM - y) / self._plot_height(), 0.0), 1.0))

    def _y(self, opacity: float) -> float:
        return self.height() - BOTTOM - opacity * self._plot_height()

    def position_of(self, value: float, opacity: float) -> QPoint:
        """Where (value, opacity) is drawn, in this widget's pixels (rounded)."""
        return QPoint(round(self._axis.to_x(value, self.width())), round(self._y(opacity)))

    def point_positions(self) -> list[QPoint]:
        """Widget-pixel centres of the opacity points, in point order."""
        tf = self.transfer_function()
        return [] if tf is None else [self.position_of(x, a) for x, a in tf.opacity_points]

    def _pick(self, pos: QPointF) -> int | None:
        tf = self.transfer_function()
        if tf is None:
            return None
        points = tf.opacity_points
        dx = self._axis.to_x(points[:, 0], self.width()) - pos.x()
        dy = np.array([self._y(a) for a in points[:, 1]]) - pos.y()
        distance = np.hypot(dx, dy)
        best = int(np.argmin(distance))
        return best if distance[best] <= PICK_RADIUS else None

    # ------------------------------------------------------------------ edits
    def add_point(self, value: float, opacity: float) -> int:
        """Add an opacity point (value clamped to the limits); returns its index."""
        tf = self.transfer_function()
        assert tf is not None
        points = tf.opacity_points
        value = self._limits.clamp(value)
        index = int(np.searchsorted(points[:, 0], value, side="right"))
        tf.set_opacity_points(np.insert(points, index, [value, min(max(opacity, 0.0), 1.0)], axis=0))
        return index

    def _add_at(self, pos: QPointF) -> int:
        return self.add_point(self.value_at(pos.x()), self.opacity_at(pos.y()))

    def _move(self, index: int, pos: QPointF) -> None:
        tf = self.transfer_function()
        if tf is None or index >= len(tf.opacity_points):
            return
        points = tf.opacity_points
        left, right = neighbours(points[:, 0], index)
        moved = (self._limits.clamp(self.value_at(pos.x()), left, right), self.opacity_at(pos.y()))
        if moved != tuple(points[index]):
            points[index] = moved
            tf.set_opacity_points(points)

    # ------------------------------------------------------------------ mouse and keys
    # ------------------------------------------------------------------ painting
    def paintEvent(self, event: QPaintEvent) -> None:
        painter = QPainter(self)
        palette = self.palette()
        painter.fillRect(self.rect(), palette.color(QPalette.Base))
        left, right = MARGIN, self.width() - MARGIN
        plot = QRectF(left, TOP, right - left, self._plot_height())
        painter.setPen(palette.color(QPalette.Mid))
        painter.drawRect(plot)
        self._paint_histogram(painter, palette)
        tf = self.transfer_function()
        if tf is None:
            return
        painter.setRenderHint(QPainter.Antialiasing)
        points = tf.opacity_points
        xs = self._axis.to_x(points[:, 0], self.width())
        # constant beyond the end points; zoomed in, those may lie outside the plot: the curve
        # then runs from them, so the area under it never folds back on itself
        start, end = min(left, float(xs[0])), max(right, float(xs[-1]))
        curve = [QPointF(start, self._y(points[0, 1]))]
        curve += [QPointF(x, self._y(a)) for x, a in zip(xs, points[:, 1])]
        curve.append(QPointF(end, self._y(points[-1, 1])))
        under = QPainterPath()
        under.addPolygon(QPolygonF([QPointF(start, plot.bottom()), *curve, QPointF(end, plot.bottom())]))
        painter.save()
        painter.setClipPath(under)
        painter.setOpacity(FILL_OPACITY)
        painter.drawImage(plot, color_strip(tf, self._axis, self.width()), QRectF(left, 0, plot.width(), 1))
        painter.restore()
        painter.setPen(QPen(palette.color(QPalette.Text), 1.5))
        painter.drawPolyline(QPolygonF(curve))
        self._paint_points(painter, tf, palette)
        labels = self.view_labels()
        if labels is not None:
            painter.setPen(palette.color(QPalette.Text))
            inside = plot.adjusted(3, 0, -3, -2)
            painter.drawText(inside, int(Qt.AlignLeft | Qt.AlignBottom), labels[0])
            painter.drawText(inside, int(Qt.AlignRight | Qt.AlignBottom), labels[1])

    def _paint_histogram(self, painter: QPainter, palette: QPalette) -> None:
        """The histogram's bars, drawn once into a pixmap kept until the histogram, the scale, the
        axis, the size or the colours change: a TF drag repaints this widget at the mouse's rate,
        and drawing the bars one by one took 1.5 ms of every repaint."""
        if self._histogram is None:
            return
        text = palette.color(QPalette.Text)
        ratio = self.devicePixelRatioF()
        key = (
            id(self._histogram),
            self._log_counts,
            self._axis,
            self.width(),
            self.height(),
            text.rgba(),
            ratio,
        )
        if self._histogram_layer is None or self._histogram_layer[0] != key:
            layer = QPixmap(round(self.width() * ratio), round(self.height() * ratio))
            layer.setDevicePixelRatio(ratio)
            layer.fill(Qt.transparent)
            bars = QPainter(layer)
            heights = self._histogram.heights(self._log_counts)
            xs = self._axis.to_x(self._histogram.edges, self.width())
            bar = QColor(text)
            bar.setAlphaF(0.22)
            bottom = self.height() - BOTTOM
            # zoomed in, most bars may lie outside: draw only the visible part of each
            xs = np.clip(xs, -1.0, self.width() + 1.0)
            for x0, x1, h in zip(xs[:-1], xs[1:], heights):
                if h > 0 and x1 > x0:
                    top = bottom - h * self._plot_height()
                    bars.fillRect(QRectF(x0, top, max(x1 - x0, 1.0), bottom - top), bar)
            bars.end()
            self._histogram_layer = (key, layer)
        painter.drawPixmap(0, 0, self._histogram_layer[1])

    def _paint_points(self, painter: QPainter, tf: TransferFunction1D, palette: QPalette) -> None:
        points = tf.opacity_points
        colors, _ = tf.sample(points[:, 0])  # all at once: one sample call per point cost a repaint 0.5 ms
        for index, (x, a) in enumerate(points):
            chosen = index == self.selected
            painter.setPen(
                QPen(palette.color(QPalette.Highlight if chosen else QPalette.Text), 2 if chosen else 1)
            )
            painter.setBrush(QColor.fromRgbF(*(float(c) for c in colors[index])))
            radius = 5.5 if chosen else 4.0
            painter.drawEllipse(QPointF(self._axis.to_x(x, self.width()), self._y(a)), radius, radius)
            if chosen:
                painter.setPen(palette.color(QPalette.Text))
                painter.drawText(QPointF(MARGIN + 4, TOP + 12), f"value {x:.5g}   opacity {a:.3f}")
