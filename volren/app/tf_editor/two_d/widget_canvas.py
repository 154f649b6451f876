"""The 2D TF editor's canvas: the joint histogram with the TF's widgets on top, edited by mouse.

Why a widget of its own: it owns the mapping between pixels and (value, gradient magnitude) and
the mouse gestures, while the surrounding editor owns buttons and the state subscription. Value
runs left to right over the TF's value range, gradient magnitude bottom to top over [0, gmax].

Gestures: a click selects the topmost widget under the mouse (or clears the selection); a drag
inside a widget moves it, a drag on a handle of the selected widget resizes it
(`core.tf_widget_geometry` says what each handle does); Delete or Backspace removes the selected
widget. A drag is wrapped in `state.begin_interaction()` / `end_interaction()` (begun at the
first movement, so a plain click is no interaction), which makes it cheap previews while it lasts
and one undo step. Every drag position is computed from the widget as it was at the press, so
rounding never accumulates.

While the mouse is over the plot, a readout in its top-right corner says what is under it
(as ParaView and Slicer show it): the value and gradient magnitude of that pixel, the
joint histogram's count in that bin and the TF's opacity there. It goes when the mouse leaves.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from PyQt5.QtCore import QEvent, QPoint, QPointF, QRectF, QSize, Qt, pyqtSignal
from PyQt5.QtGui import (
    QColor,
    QImage,
    QKeyEvent,
    QLinearGradient,
    QMouseEvent,
    QPainter,
    QPaintEvent,
    QPen,
    QPolygonF,
)
from PyQt5.QtWidgets import QSizePolicy, QWidget

from volren.app.core import tf_widget_geometry as geometry
from volren.app.core.joint_histogram import JointHistogram
from volren.app.core.state import ViewState
from volren.errors import VolrenError
from volren.model.transfer_function_2d import TFWidget, TransferFunction2D

#: Pixels around a handle that grab it.
HANDLE_RADIUS = 6.0
#: Margins around the plot (left, top, right, bottom); the bottom one holds the value labels.
MARGINS = (6.0, 6.0, 6.0, 18.0)
#: The smallest widget size a resize leaves, as a fraction of each axis.
MIN_SIZE_FRACTION = 1e-3
#: Most colour stops a 1d widget's fill has (a 1D TF may have thousands of points).
BAND_STOPS = 256

_BACKGROUND = QColor(28, 28, 32)
_EMPTY_PLOT = QColor(12, 12, 14)
_OUTLINE = QColor(230, 230, 230)
_SELECTED = QColor(255, 210, 60)
_LABEL = QColor(190, 190, 190)
_READOUT_BACK = QColor(0, 0, 0, 170)


@dataclass(frozen=True)
class HoverReadout:
    """What is under the mouse: a point of the plot, its histogram bin and the TF there."""

    value: float
    gradient: float
    #: The joint histogram's count in the bin holding (value, gradient); None without a histogram.
    count: float | None
    opacity: float

    def lines(self) -> tuple[str, str]:
        count = "-" if self.count is None else f"{self.count:.6g}"
        return (
            f"value {self.value:.5g}  |grad| {self.gradient:.4g}",
            f"count {count}  opacity {self.opacity:.3f}",
        )


def histogram_count(histogram: JointHistogram, value: float, gradient: float) -> float | None:
    """The count of the bin holding (value, gradient) (`JointHistogram`'s bins: half-open, the
    top edges closed); None outside the histogram."""
    lo, hi = histogram.value_range
    gmax = histogram.gradient_max
    if not (lo <= value <= hi and 0.0 <= gradient <= gmax):
        return None
    n_gradients, n_values = histogram.shape
    i = min(int((value - lo) * (n_values / (hi - lo))), n_values - 1)
    j = min(int(gradient * (n_gradients / gmax)), n_gradients - 1)
    return float(histogram.counts[j, i])


class _Drag:
    """A drag in progress: which widget, which handle (None: move), and the state at the press."""

    def __init__(
        self, tf: TransferFunction2D, index: int, handle: str | None, start: tuple[float, float]
    ) -> None:
        self.tf = tf
        self.index = index
        self.handle = handle
        self.start = start
        self.original: TFWidget = tf.widgets[index]
        self.interacting = False


class TFWidgetCanvas(QWidget):
    """Draws and edits the widgets of the 2D TF it is given (it never replaces the TF object)."""

    #: The selected widget's index, -1 for none.
    selectionChanged = pyqtSignal(int)
    #: (title, one-line message).
    errorOccurred = pyqtSignal(str, str)

    def __init__(self, state: ViewState, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._state = state
        self._tf: TransferFunction2D | None = None
        self._histogram: JointHistogram | None = None
        self._image: QImage | None = None
        self._selected: int | None = None
        self._drag: _Drag | None = None
        self._hover: QPointF | None = None  # the mouse over the plot, for the readout
        self.setFocusPolicy(Qt.StrongFocus)
        self.setMouseTracking(True)
        self.setSizePolicy(QSizePolicy.Expanding, QSizePolicy.Expanding)
        self.setMinimumSize(200, 120)
        self.setToolTip(
            "Click: select; drag: move; drag a handle: resize; Delete: remove the selected widget"
        )

    def sizeHint(self) -> QSize:
        return QSize(320, 260)

    # ------------------------------------------------------------------ inputs
    @property
    def transfer_function(self) -> TransferFunction2D | None:
        return self._tf

    def set_transfer_function(self, tf: TransferFunction2D | None) -> None:
        """Show `tf` (called after every change); a new object ends a drag on the old one."""
        if tf is not self._tf:
            self._finish_drag()
        self._tf = tf
        count = len(tf.widgets) if tf is not None else 0
        if self._selected is not None and self._selected >= count:
            self.select(None)
        self.update()

    def set_histogram(self, histogram: JointHistogram | None) -> None:
        """The background: log density as greyscale, highest gradient row at the top."""
        self._histogram = histogram
        self._image = None
        if histogram is not None:
            grey = np.ascontiguousarray(np.round(histogram.log_density[::-1] * 255.0).astype(np.uint8))
            height, width = grey.shape
            self._image = QImage(grey.data, width, height, width, QImage.Format_Grayscale8).copy()
        self.update()

    @property
    def histogram(self) -> JointHistogram | None:
        return self._histogram

    # ------------------------------------------------------------------ selection
    @property
    def selected(self) -> int | None:
        return self._selected

    def select(self, index: int | None) -> None:
        if index is not None and (self._tf is None or not 0 <= index < len(self._tf.widgets)):
            index = None
        if index == self._selected:
            return
        self._selected = index
        self.update()
        self.selectionChanged.emit(-1 if index is None else index)

    def delete_selected(self) -> None:
        """Remove the selected widget (the selection moves to nothing)."""
        if self._tf is None or self._selected is None:
            return
        index = self._selected
        self.select(None)
        self._tf.remove_widget(index)

    # ------------------------------------------------------------------ coordinates
    def plot_rect(self) -> QRectF:
        left, top, right, bottom = MARGINS
        return QRectF(
            left, top, max(1.0, self.width() - left - right), max(1.0, self.height() - top - bottom)
        )

    def _axes(self) -> tuple[float, float, float]:
        if self._tf is None:
            return 0.0, 1.0, 1.0
        lo, hi = self._tf.value_range
        return lo, hi, self._tf.gradient_range[1]

    def to_pixel(self, s: float, g: float) -> QPointF:
        """Canvas pixel of (value, gradient magnitude)."""
        lo, hi, gmax = self._axes()
        r = self.plot_rect()
        return QPointF(r.left() + (s - lo) / (hi - lo) * r.width(), r.bottom() - g / gmax * r.height())

    def to_data(self, point: QPointF | QPoint) -> tuple[float, float]:
        """(value, gradient magnitude) at a canvas pixel."""
        lo, hi, gmax = self._axes()
        r = self.plot_rect()
        return (
            lo + (point.x() - r.left()) / r.width() * (hi - lo),
            (r.bottom() - point.y()) / r.height() * gmax,
        )

    def minimum_size(self) -> tuple[float, float]:
        """The smallest (value, gradient) size a resize leaves."""
        lo, hi, gmax = self._axes()
        return (MIN_SIZE_FRACTION * (hi - lo), MIN_SIZE_FRACTION * gmax)

    def widget_pixel(self, index: int) -> QPoint:
        """The pixel a move grabs widget `index` at (its `core.tf_widget_geometry.center`)."""
        assert self._tf is not None
        return self.to_pixel(*geometry.center(self._tf.widgets[index])).toPoint()

    def handle_names(self, index: int) -> tuple[str, ...]:
        assert self._tf is not None
        return tuple(geometry.handles(self._tf.widgets[index]))

    def handle_pixel(self, index: int, handle: str) -> QPoint:
        """The pixel of `handle` of widget `index` (a drag there resizes once it is selected)."""
        assert self._tf is not None
        return self.to_pixel(*geometry.handles(self._tf.widgets[index])[handle]).toPoint()

    def widget_at(self, point: QPointF | QPoint) -> int | None:
        """The topmost (last drawn) widget whose outline holds the pixel."""
        if self._tf is None:
            return None
        s, g = self.to_data(point)
        for index in range(len(self._tf.widgets) - 1, -1, -1):
            if geometry.contains(self._tf.widgets[index], s, g):
                return index
        return None

    def handle_at(self, point: QPointF | QPoint) -> str | None:
        """The selected widget's handle within HANDLE_RADIUS pixels of `point`, nearest first."""
        if self._tf is None or self._selected is None:
            return None
        best, best_d = None, HANDLE_RADIUS
        for name, (s, g) in geometry.handles(self._tf.widgets[self._selected]).items():
            p = self.to_pixel(s, g)
            d = math.hypot(p.x() - point.x(), p.y() - point.y())
            if d <= best_d:
                best, best_d = name, d
        return best

    # ------------------------------------------------------------------ hover readout
    def hover_readout(self) -> HoverReadout | None:
        """What the readout shows now: None unless the mouse is over the plot of a TF."""
        if self._hover is None or self._tf is None:
            return None
        s, g = self.to_data(self._hover)
        count = None if self._histogram is None else histogram_count(self._histogram, s, g)
        _, opacity = self._tf.sample(s, g)
        return HoverReadout(s, g, count, float(opacity))

    def _set_hover(self, point: QPointF | None) -> None:
        if point is not None and not self.plot_rect().contains(point):
            point = None
        if point != self._hover:
            self._hover = point
            self.update()

    def leaveEvent(self, event: QEvent) -> None:
        self._set_hover(None)
        super().leaveEvent(event)

    # ------------------------------------------------------------------ mouse and keys
    def mousePressEvent(self, event: QMouseEvent) -> None:
        if event.button() != Qt.LeftButton or self._tf is None or self._drag is not None:
            return super().mousePressEvent(event)
        self.setFocus(Qt.MouseFocusReason)
        handle = self.handle_at(event.pos())
        if handle is not None:
            assert self._selected is not None
            index = self._selected
        else:
            index = self.widget_at(event.pos())
            self.select(index)
        if index is not None:
            self._drag = _Drag(self._tf, index, handle, self.to_data(event.pos()))
        event.accept()

    def mouseMoveEvent(self, event: QMouseEvent) -> None:
        self._set_hover(event.localPos())
        drag = self._drag
        if drag is None:
            self._update_cursor(event.pos())
            return super().mouseMoveEvent(event)
        if drag.tf is not self._tf or drag.index >= len(drag.tf.widgets):
            self._finish_drag()
            return
        s, g = self.to_data(event.pos())
        if drag.handle is None:
            widget = geometry.moved(drag.original, s - drag.start[0], g - drag.start[1])
        else:
            widget = geometry.resized(drag.original, drag.handle, s, g, self.minimum_size())
        if widget != drag.tf.widgets[drag.index]:
            if not drag.interacting:
                drag.interacting = True
                self._state.begin_interaction()
            try:
                drag.tf.replace_widget(drag.index, widget)
            except VolrenError as exc:
                self.errorOccurred.emit("Cannot edit the widget", str(exc))
        event.accept()

    def mouseReleaseEvent(self, event: QMouseEvent) -> None:
        if event.button() != Qt.LeftButton or self._drag is None:
            return super().mouseReleaseEvent(event)
        self._finish_drag()
        event.accept()

    def _finish_drag(self) -> None:
        drag, self._drag = self._drag, None
        if drag is not None and drag.interacting:
            self._state.end_interaction()

    def _update_cursor(self, point: QPoint) -> None:
        if self.handle_at(point) is not None:
            self.setCursor(Qt.CrossCursor)
        elif self.widget_at(point) is not None:
            self.setCursor(Qt.SizeAllCursor)
        else:
            self.unsetCursor()

    def keyPressEvent(self, event: QKeyEvent) -> None:
        if event.key() in (Qt.Key_Delete, Qt.Key_Backspace) and self._selected is not None:
            self.delete_selected()
            event.accept()
            return
        super().keyPressEvent(event)

    # ------------------------------------------------------------------ painting
    def paintEvent(self, event: QPaintEvent) -> None:
        painter = QPainter(self)
        painter.fillRect(self.rect(), _BACKGROUND)
        plot = self.plot_rect()
        if self._image is not None:
            painter.setRenderHint(QPainter.SmoothPixmapTransform, True)
            painter.drawImage(plot, self._image)
        else:
            painter.fillRect(plot, _EMPTY_PLOT)
        if self._tf is None:
            return
        painter.setRenderHint(QPainter.Antialiasing, True)
        painter.save()
        painter.setClipRect(plot)
        for index, widget in enumerate(self._tf.widgets):
            self._paint_widget(painter, widget, index == self._selected)
        painter.restore()
        self._paint_labels(painter, plot)
        self._paint_readout(painter, plot)

    def _paint_widget(self, painter: QPainter, widget: TFWidget, selected: bool) -> None:
        if widget.type == "1d":
            painter.setBrush(self._band_brush(widget))
        else:
            r, g, b = widget.color
            painter.setBrush(QColor.fromRgbF(r, g, b, widget.opacity))
        painter.setPen(QPen(_SELECTED if selected else _OUTLINE, 2.0 if selected else 1.0))
        painter.drawPolygon(QPolygonF([self.to_pixel(s, gm) for s, gm in geometry.outline(widget)]))
        if selected:
            painter.setBrush(_SELECTED)
            painter.setPen(QPen(Qt.black, 1.0))
            half = HANDLE_RADIUS / 2.0
            for s, gm in geometry.handles(widget).values():
                p = self.to_pixel(s, gm)
                painter.drawRect(QRectF(p.x() - half, p.y() - half, 2 * half, 2 * half))

    def _band_brush(self, widget: TFWidget) -> QLinearGradient:
        """A 1d widget's fill: its colour and opacity along value, as the other widgets show theirs."""
        xs = widget.profile().breakpoints()
        if len(xs) > BAND_STOPS:
            xs = np.linspace(xs[0], xs[-1], BAND_STOPS)
        rgb = widget.color_at(xs)
        alpha = widget.opacity_at(xs, widget.gradient_range[0])  # type: ignore[index]
        gradient = QLinearGradient(self.to_pixel(xs[0], 0.0), self.to_pixel(xs[-1], 0.0))
        span = xs[-1] - xs[0]
        for x, (r, g, b), a in zip(xs, rgb, alpha, strict=True):
            gradient.setColorAt((x - xs[0]) / span if span > 0 else 0.0, QColor.fromRgbF(r, g, b, a))
        return gradient

    def _paint_labels(self, painter: QPainter, plot: QRectF) -> None:
        lo, hi, gmax = self._axes()
        painter.setPen(_LABEL)
        below = QRectF(plot.left(), plot.bottom() + 1.0, plot.width(), MARGINS[3] - 1.0)
        painter.drawText(below, int(Qt.AlignLeft | Qt.AlignVCenter), f"{lo:.4g}")
        painter.drawText(below, int(Qt.AlignHCenter | Qt.AlignVCenter), "value")
        painter.drawText(below, int(Qt.AlignRight | Qt.AlignVCenter), f"{hi:.4g}")
        inside = plot.adjusted(4.0, 2.0, -4.0, -2.0)
        painter.drawText(inside, int(Qt.AlignLeft | Qt.AlignTop), f"|grad| {gmax:.4g}")
        painter.drawText(inside, int(Qt.AlignLeft | Qt.AlignBottom), "0")

    def _paint_readout(self, painter: QPainter, plot: QRectF) -> None:
        readout = self.hover_readout()
        if readout is None:
            return
        lines = readout.lines()
        metrics = painter.fontMetrics()
        width = max(metrics.horizontalAdvance(line) for line in lines) + 8
        height = metrics.height() * len(lines) + 4
        box = QRectF(plot.right() - width - 2, plot.top() + 2, width, height)
        painter.fillRect(box, _READOUT_BACK)
        painter.setPen(_OUTLINE)
        painter.drawText(box.adjusted(4, 2, -4, -2), int(Qt.AlignLeft | Qt.AlignTop), "\n".join(lines))
