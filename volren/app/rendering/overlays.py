"""The viewport's overlays: the volume's outline, the orientation axes, the colour legend, and
the crop box's edges and face handles while the box is edited in the view, and a clip plane's outline
and handles while it is.

Why painted by the viewport rather than rendered: they must never cost a frame. Each paint draws
them with QPainter over the frame image (a dozen lines, three arms, and a strip and a curve of a
few hundred TF samples: well under a millisecond), so toggling one only repaints, and every
renderer gets them alike. Their geometry comes from `core.overlay_geometry`, with the camera the
frame was rendered with, so the outline lines up with the volume even while a newer frame is
still being drawn. A 2D TF gets no legend: its colour depends on the gradient magnitude as well
as the value, so no single bar shows it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, fields

import numpy as np
from PyQt5.QtCore import QLineF, QPointF, QRectF, Qt
from PyQt5.QtGui import QColor, QFont, QImage, QPainter, QPen, QPolygonF

from volren.app.core.crop_handles import face_axis, handle_depths, handle_pixels
from volren.app.core.overlay_geometry import Rect, outline_segments, project_points, triad_arms
from volren.app.core.plane_handles import handle_points as plane_handle_points
from volren.app.core.plane_handles import plane_polygon
from volren.model.camera import Camera
from volren.model.clip_region import ClipPlane
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TransferFunction

#: ParaView's outline colour; nothing else the overlays draw is pure white.
OUTLINE_COLOR = QColor(255, 255, 255)
#: X red, Y green, Z blue, as in ParaView's and Slicer's orientation markers.
AXIS_COLORS = (QColor(235, 60, 60), QColor(60, 210, 60), QColor(80, 130, 255))
AXIS_NAMES = ("X", "Y", "Z")
#: The triad's arm length, the room its labels take beyond the arms, and its distance from the
#: lower-left corner (widget pixels).
TRIAD_LENGTH = 32.0
TRIAD_LABEL_ROOM = 14.0
TRIAD_MARGIN = 8.0
#: The legend's bar: width, share of the viewport's height (at most LEGEND_MAX_HEIGHT), margin
#: from the right edge, and the width of the opacity curve drawn to the bar's left.
LEGEND_WIDTH = 14.0
LEGEND_HEIGHT_SHARE = 0.5
LEGEND_MAX_HEIGHT = 320.0
LEGEND_MARGIN = 14.0
OPACITY_WIDTH = 24.0
LEGEND_TEXT_COLOR = QColor(225, 225, 225)
OPACITY_COLOR = QColor(240, 240, 160)
#: The crop box's edges while its handles are shown: amber, apart from the white outline.
CROP_BOX_COLOR = QColor(255, 190, 40)
#: The handles: discs in their axis's colour with a dark rim; the one under the mouse (or being
#: dragged) larger and lighter.
HANDLE_RADIUS = 5.0
HOT_HANDLE_RADIUS = 7.0
HANDLE_RIM_COLOR = QColor(20, 20, 20)
HOT_HANDLE_LIGHTER = 160


@dataclass
class OverlaySettings:
    """Which overlays the viewport draws (the View menu's checkable actions, with their defaults)."""

    outline: bool = True
    axes: bool = True
    legend: bool = False

    @classmethod
    def names(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))


def draw_outline(
    painter: QPainter, camera: Camera, aspect: float, rect: Rect, bounds: Sequence[float]
) -> None:
    """The 12 edges of `bounds`, 1-pixel white lines without antialiasing (crisp on any frame)."""
    segments = outline_segments(camera, aspect, rect, bounds)
    painter.save()
    painter.setRenderHint(QPainter.Antialiasing, False)
    painter.setPen(QPen(OUTLINE_COLOR, 1.0))
    painter.drawLines([QLineF(a[0], a[1], b[0], b[1]) for a, b in segments])
    painter.restore()


def handle_color(face: int, hot: bool) -> QColor:
    """A face handle's fill: its axis's colour, lighter while under the mouse or dragged."""
    color = AXIS_COLORS[face_axis(face)]
    return color.lighter(HOT_HANDLE_LIGHTER) if hot else QColor(color)


def draw_crop_handles(painter: QPainter, camera: Camera, aspect: float, rect: Rect, box: Sequence[float],
                      hot: int | None = None) -> None:  # fmt: skip
    """The crop box's 12 edges and a disc at the centre of each face, far handles first so that
    nearer ones cover them; `hot` (a face, `Box` order) is drawn larger and lighter."""
    segments = outline_segments(camera, aspect, rect, box)
    pixels = handle_pixels(camera, aspect, rect, box)
    order = np.argsort(-handle_depths(camera, box), kind="stable")
    painter.save()
    painter.setRenderHint(QPainter.Antialiasing, False)
    painter.setPen(QPen(CROP_BOX_COLOR, 1.0))
    painter.drawLines([QLineF(a[0], a[1], b[0], b[1]) for a, b in segments])
    painter.setRenderHint(QPainter.Antialiasing, True)
    painter.setPen(QPen(HANDLE_RIM_COLOR, 1.0))
    for face in (int(f) for f in order):
        x, y = pixels[face]
        if not (np.isfinite(x) and np.isfinite(y)):
            continue
        radius = HOT_HANDLE_RADIUS if face == hot else HANDLE_RADIUS
        painter.setBrush(handle_color(face, face == hot))
        painter.drawEllipse(QPointF(float(x), float(y)), radius, radius)
    painter.restore()


#: A clip plane's outline and arrow while its handles are shown: cyan, apart from the amber crop box.
CLIP_PLANE_COLOR = QColor(80, 220, 255)


def draw_plane_handles(painter: QPainter, camera: Camera, aspect: float, rect: Rect, plane: ClipPlane,
                       bounds: Sequence[float], hot: str | None = None) -> None:  # fmt: skip
    """A clip plane's outline across the volume's box, the arrow of its kept side's normal, a disc
    at its centre (move) and one at the arrow's tip (turn); `hot` ("move" or "turn") larger and
    lighter."""
    polygon = project_points(camera, aspect, rect, plane_polygon(plane, bounds))
    handles = project_points(camera, aspect, rect, plane_handle_points(plane, bounds))
    painter.save()
    painter.setRenderHint(QPainter.Antialiasing, True)
    painter.setPen(QPen(CLIP_PLANE_COLOR, 1.5))
    points = [QPointF(float(x), float(y)) for x, y in polygon if np.isfinite(x) and np.isfinite(y)]
    if len(points) >= 3:
        painter.drawPolygon(QPolygonF(points))
    (cx, cy), (tx, ty) = handles
    if all(np.isfinite(v) for v in (cx, cy, tx, ty)):
        painter.drawLine(QLineF(cx, cy, tx, ty))
    painter.setPen(QPen(HANDLE_RIM_COLOR, 1.0))
    for kind, (x, y) in zip(("move", "turn"), handles, strict=True):
        if np.isfinite(x) and np.isfinite(y):
            radius = HOT_HANDLE_RADIUS if kind == hot else HANDLE_RADIUS
            painter.setBrush(
                CLIP_PLANE_COLOR.lighter(HOT_HANDLE_LIGHTER) if kind == hot else CLIP_PLANE_COLOR
            )
            painter.drawEllipse(QPointF(float(x), float(y)), radius, radius)
    painter.restore()


def triad_origin(widget_height: float) -> QPointF:
    """Where the triad's arms start: in from the lower-left corner by an arm and its label, so that
    every arm and label stays inside the viewport however the camera turns."""
    inset = TRIAD_MARGIN + TRIAD_LABEL_ROOM + TRIAD_LENGTH
    return QPointF(inset, widget_height - inset)


def draw_axes(painter: QPainter, camera: Camera, widget_height: float) -> None:
    """The world axes as the camera turns them, labelled, in the lower-left corner."""
    origin = triad_origin(widget_height)
    offsets, order = triad_arms(camera, TRIAD_LENGTH)
    painter.save()
    painter.setRenderHint(QPainter.Antialiasing, True)
    font = QFont(painter.font())
    font.setBold(True)
    painter.setFont(font)
    metrics = painter.fontMetrics()
    for axis in order:
        dx, dy = offsets[axis]
        color = AXIS_COLORS[axis]
        end = QPointF(origin.x() + dx, origin.y() + dy)
        painter.setPen(QPen(color, 2.0, Qt.SolidLine, Qt.RoundCap))
        painter.drawLine(QLineF(origin, end))
        # The label sits just beyond the arm's end (or on the origin's corner when it points at us).
        norm = float(np.hypot(dx, dy))
        ux, uy = (dx / norm, dy / norm) if norm > 1e-6 else (0.7, -0.7)
        label = QPointF(end.x() + 0.6 * TRIAD_LABEL_ROOM * ux, end.y() + 0.6 * TRIAD_LABEL_ROOM * uy)
        half = metrics.horizontalAdvance("X")
        box = QRectF(label.x() - half, label.y() - metrics.height() / 2.0, 2 * half, metrics.height())
        painter.drawText(box, Qt.AlignCenter, AXIS_NAMES[axis])
    painter.restore()


def legend_bar_rect(widget_width: float, widget_height: float) -> QRectF:
    """The colour bar's rectangle: at the right edge, centred vertically."""
    height = min(LEGEND_HEIGHT_SHARE * widget_height, LEGEND_MAX_HEIGHT)
    return QRectF(
        widget_width - LEGEND_MARGIN - LEGEND_WIDTH, (widget_height - height) / 2.0, LEGEND_WIDTH, height
    )


def legend_samples(tf: TransferFunction1D, rows: int) -> tuple[np.ndarray, np.ndarray, tuple[float, float]]:
    """Colours (rows, 3) and opacities (rows,) of the TF from the top row (its range's maximum) to
    the bottom row (its minimum), sampled at the rows' centres, and that range."""
    lo, hi = tf.value_range
    rows = max(int(rows), 1)
    values = hi - (np.arange(rows) + 0.5) / rows * (hi - lo)
    rgb, alpha = tf.sample(values)
    return rgb, alpha, (lo, hi)


def range_texts(value_range: tuple[float, float]) -> tuple[str, str]:
    """The numbers written above (the maximum) and below (the minimum) the colour bar."""
    lo, hi = value_range
    return f"{hi:.4g}", f"{lo:.4g}"


def draw_legend(painter: QPainter, tf: TransferFunction, widget_width: float, widget_height: float) -> None:
    """The 1D TF's colours as a vertical bar with its opacity as a curve to its left and the TF's
    range (max on top, min below). A 2D TF has no single colour per value: no legend."""
    if not isinstance(tf, TransferFunction1D):
        return
    bar = legend_bar_rect(widget_width, widget_height)
    rows = max(round(bar.height()), 1)
    rgb, alpha, (lo, hi) = legend_samples(tf, rows)
    pixels = np.ascontiguousarray(np.round(rgb * 255.0).astype(np.uint8).reshape(rows, 1, 3))
    strip = QImage(pixels.data, 1, rows, 3, QImage.Format_RGB888)
    painter.save()
    painter.setRenderHint(QPainter.SmoothPixmapTransform, False)
    painter.drawImage(bar, strip)
    painter.setRenderHint(QPainter.Antialiasing, False)
    painter.setPen(QPen(LEGEND_TEXT_COLOR, 1.0))
    painter.drawRect(bar.adjusted(-1.0, -1.0, 0.0, 0.0))
    curve = QRectF(bar.left() - 3.0 - OPACITY_WIDTH, bar.top(), OPACITY_WIDTH, bar.height())
    painter.fillRect(curve, QColor(0, 0, 0, 110))
    ys = bar.top() + (np.arange(rows) + 0.5) / rows * bar.height()
    xs = curve.left() + alpha * curve.width()
    painter.setRenderHint(QPainter.Antialiasing, True)
    painter.setPen(QPen(OPACITY_COLOR, 1.5))
    painter.drawPolyline(QPolygonF([QPointF(float(x), float(y)) for x, y in zip(xs, ys, strict=True)]))
    painter.setPen(LEGEND_TEXT_COLOR)
    metrics = painter.fontMetrics()
    for text, y in zip(
        range_texts((lo, hi)), (bar.top() - 4.0 - metrics.height(), bar.bottom() + 4.0), strict=True
    ):
        painter.drawText(
            QRectF(bar.right() - 200.0, y, 200.0, metrics.height()), Qt.AlignRight | Qt.AlignVCenter, text
        )
    painter.restore()
