"""The viewport: paints the latest frame and turns mouse gestures into camera changes.

Every renderer draws offscreen into an array, so the viewport is a plain QWidget that paints a
QImage; no renderer needs a window of its own, and switching renderers never rebuilds widgets.
Frames keep their aspect ratio (a frame made before a resize is letterboxed until its successor
arrives) and preview frames are scaled up smoothly.

Gestures follow VTK's trackball camera (see `core.interaction`): left-drag rotates, right-drag or the
wheel dollies, middle-drag (or shift + left-drag) pans, 'r' resets the view; ctrl + left-click
emits `pointPicked` with the pixel under the mouse (for picking). The viewport only
changes the `ViewState`; the frame scheduler decides what to render.

Over the frame it paints the overlays of `rendering.overlays` (outline, orientation axes, colour
legend), each paint, with the camera the frame was rendered with; `set_overlay` toggles one and
only repaints.

`set_clip_handles(index)` (View > Edit clip plane, for the plane selected in the clipping panel)
paints that plane's outline across the volume with a handle at its centre, dragged to move the
plane along its normal, and one at the tip of its normal, dragged to turn it (Shift: to the
nearest axis) (`core.plane_handles`), as one interaction each.

`set_crop_handles(True)` (View > Edit crop box) also paints the crop box (the whole volume when
nothing is cropped) with a handle on each face (`core.crop_handles`). A plain left-press on a
handle then drags that face along its axis instead of rotating, as one interaction: the state's
crop box changes with each move (previews) and one full frame follows the release. Hovering a
handle lights it and shows a size cursor along the face's axis on screen.
"""

from __future__ import annotations

import math

from PyQt5.QtCore import QEvent, QPoint, QRectF, QSize, Qt, pyqtSignal
from PyQt5.QtGui import (
    QColor,
    QCursor,
    QImage,
    QKeyEvent,
    QMouseEvent,
    QPainter,
    QPaintEvent,
    QResizeEvent,
    QWheelEvent,
)
from PyQt5.QtWidgets import QSizePolicy, QWidget

from volren.app.core import interaction
from volren.app.core.crop_handles import FaceDrag, handle_at, minimum_thickness, shown_box
from volren.app.core.overlay_geometry import Rect
from volren.app.core.plane_handles import PlaneDrag
from volren.app.core.plane_handles import handle_at as plane_handle_at
from volren.app.core.state import ViewState
from volren.app.rendering.overlays import (
    OverlaySettings,
    draw_axes,
    draw_crop_handles,
    draw_legend,
    draw_outline,
    draw_plane_handles,
)
from volren.app.rendering.render_service import Frame
from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.clip_region import ClipPlane, ClipRegion
from volren.model.crop import Box

_GESTURES = {Qt.LeftButton: "rotate", Qt.RightButton: "dolly", Qt.MiddleButton: "pan"}
#: The size cursor of each `core.crop_handles.cursor_kind`.
_SIZE_CURSORS = {"horizontal": Qt.SizeHorCursor, "vertical": Qt.SizeVerCursor,
                 "rising": Qt.SizeBDiagCursor, "falling": Qt.SizeFDiagCursor}  # fmt: skip


class Viewport(QWidget):
    """Shows frames of the `ViewState` it edits; `resized` and `resetRequested` go to the window."""

    resized = pyqtSignal()
    resetRequested = pyqtSignal()
    #: Ctrl+left-click: the pixel (x, y) under the mouse in a full frame of `pixel_size()` (row 0
    #: at the top), i.e. what `pick(volume, tf, state.camera, x, y, *pixel_size())` looks at.
    pointPicked = pyqtSignal(int, int)

    def __init__(self, state: ViewState, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._state = state
        self._frame: Frame | None = None
        self._image: QImage | None = None
        self._drag_button: int | None = None
        self._drag_gesture: str | None = None
        self._last_pos = QPoint()
        self._face_drag: FaceDrag | None = None
        self._face_drag_from = QPoint()
        self._hot_face: int | None = None
        #: Whether the crop box and its face handles are shown (and draggable); see `set_crop_handles`.
        self.crop_handles = False
        #: The clip plane (its index in the settings' planes) whose handles are shown, or None.
        self.clip_plane: int | None = None
        self._plane_drag: PlaneDrag | None = None
        self._hot_plane_handle: str | None = None
        self.placeholder = "No volume"
        #: The overlays drawn over frames; change them through `set_overlay`.
        self.overlays = OverlaySettings()
        self.setFocusPolicy(Qt.StrongFocus)
        self.setAttribute(Qt.WA_OpaquePaintEvent)
        self.setSizePolicy(QSizePolicy.Expanding, QSizePolicy.Expanding)
        self.setMinimumSize(64, 64)
        self.setToolTip(
            "Left-drag: rotate; right-drag or wheel: zoom; middle-drag: pan; R: reset view; "
            "Ctrl+click: place a 2D transfer-function widget at that point (with labels drawn: select the "
            "label seen there); with View > Edit crop box, "
            "drag a face's handle to crop"
        )

    # ------------------------------------------------------------------ frames
    @property
    def frame(self) -> Frame | None:
        return self._frame

    def pixel_size(self) -> tuple[int, int]:
        """The size full-quality frames are rendered at: device pixels."""
        ratio = self.devicePixelRatioF()
        return max(0, round(self.width() * ratio)), max(0, round(self.height() * ratio))

    def aspect(self) -> float:
        w, h = self.width(), self.height()
        return w / h if w > 0 and h > 0 else 1.0

    def show_frame(self, frame: Frame) -> None:
        """Display `frame` (its pixel buffer is kept alive as long as the QImage)."""
        self._frame = frame
        self._image = QImage(frame.rgb.data, frame.width, frame.height, 3 * frame.width, QImage.Format_RGB888)
        self.update()

    def clear_frame(self) -> None:
        self._frame = None
        self._image = None
        self.update()

    def sizeHint(self) -> QSize:
        return QSize(640, 480)

    def paintEvent(self, event: QPaintEvent) -> None:
        painter = QPainter(self)
        r, g, b = self._state.background
        painter.fillRect(self.rect(), QColor.fromRgbF(r, g, b))
        if self._image is None:
            painter.setPen(QColor(200, 200, 200))
            painter.drawText(self.rect(), Qt.AlignCenter, self.placeholder)
            return
        painter.setRenderHint(QPainter.SmoothPixmapTransform, True)
        target = self._target_rect()
        painter.drawImage(target, self._image)
        self._paint_overlays(painter, target)

    def set_overlay(self, name: str, visible: bool) -> None:
        """Show or hide the overlay `name` (an `OverlaySettings` field): a repaint, never a new frame."""
        if name not in OverlaySettings.names():
            raise ValueError(f"unknown overlay {name!r}; expected one of {OverlaySettings.names()}")
        setattr(self.overlays, name, bool(visible))
        self.update()

    def _paint_overlays(self, painter: QPainter, target: QRectF) -> None:
        """The overlays that are on, over the frame drawn in `target` (the frame's camera and aspect)."""
        assert self._frame is not None
        camera, bounds, tf = self._frame.camera, self._state.shown_bounds, self._state.transfer_function
        if self.overlays.outline and bounds is not None:
            rect = (target.x(), target.y(), target.width(), target.height())
            draw_outline(painter, camera, self._frame.width / self._frame.height, rect, bounds)
        view = self._handle_view()
        if view is not None:
            draw_crop_handles(painter, *view, hot=self._hot_face)
        plane_view = self._plane_view()
        if plane_view is not None:
            draw_plane_handles(painter, *plane_view, hot=self._hot_plane_handle)
        if self.overlays.axes:
            draw_axes(painter, camera, self.height())
        if self.overlays.legend and tf is not None:
            draw_legend(painter, tf, self.width(), self.height())

    def _target_rect(self) -> QRectF:
        """The largest rectangle with the frame's aspect, centred in the widget."""
        assert self._frame is not None
        fw, fh = self._frame.width, self._frame.height
        scale = min(self.width() / fw, self.height() / fh)
        w, h = fw * scale, fh * scale
        return QRectF((self.width() - w) / 2.0, (self.height() - h) / 2.0, w, h)

    # ------------------------------------------------------------------ crop handles
    def set_crop_handles(self, visible: bool) -> None:
        """Show the crop box with its face handles and let them be dragged, or hide them (a repaint)."""
        self.crop_handles = bool(visible)
        self.setMouseTracking(self.crop_handles)  # hovering lights a handle
        if not self.crop_handles:
            self._set_hot_face(None, None)
        self.update()

    @property
    def hot_face(self) -> int | None:
        """The face (`Box` order) whose handle is under the mouse or being dragged, or None."""
        return self._hot_face

    def _handle_view(self) -> tuple[Camera, float, Rect, Box] | None:
        """The camera, aspect, frame rectangle and box the handles are drawn with: the frame's
        camera, as the outline; None while the handles are off or nothing is shown."""
        volume = self._state.volume
        if not self.crop_handles or self._frame is None or volume is None:
            return None
        target = self._target_rect()
        rect = (target.x(), target.y(), target.width(), target.height())
        aspect = self._frame.width / self._frame.height
        return self._frame.camera, aspect, rect, shown_box(self._state.crop, volume.bounds)

    # ------------------------------------------------------------------ clip plane handles
    def set_clip_handles(self, index: int | None) -> None:
        """Show the handles of clip plane `index` (of the settings' planes), or none (a repaint)."""
        if index != self.clip_plane:
            self.clip_plane = index
            self._hot_plane_handle = None
            self.update()

    def _plane_view(self) -> tuple[Camera, float, Rect, ClipPlane, tuple[float, ...]] | None:
        """The camera, aspect, frame rectangle, plane and volume bounds the plane's handles are
        drawn with; None while they are hidden."""
        planes, volume = self._state.settings.clip.planes, self._state.volume
        index = self.clip_plane
        if index is None or self._frame is None or volume is None or not 0 <= index < len(planes):
            return None
        target = self._target_rect()
        rect = (target.x(), target.y(), target.width(), target.height())
        return (
            self._frame.camera,
            self._frame.width / self._frame.height,
            rect,
            planes[index],
            tuple(volume.bounds),
        )

    def _start_plane_drag(self, pos: QPoint) -> bool:
        view = self._plane_view()
        if view is None:
            return False
        kind = plane_handle_at(*view, pos.x() + 0.5, pos.y() + 0.5)
        drag = None if kind is None else PlaneDrag.start_at(kind, *view)
        if drag is None:
            return False
        self._plane_drag = drag
        self._face_drag_from = pos
        self._drag_button = Qt.LeftButton
        self._hot_plane_handle = kind
        self.setCursor(QCursor(Qt.ClosedHandCursor if kind == "turn" else _SIZE_CURSORS[drag.cursor()]))
        self._state.begin_interaction()
        return True

    def _drag_plane(self, pos: QPoint, snap: bool) -> None:
        drag, index = self._plane_drag, self.clip_plane
        assert drag is not None
        settings = self._state.settings
        planes = list(settings.clip.planes)
        if index is None or not 0 <= index < len(planes):
            return  # the plane went (undo, a scene loaded) mid-drag
        planes[index] = drag.plane_for(
            pos.x() - self._face_drag_from.x(), pos.y() - self._face_drag_from.y(), snap
        )
        self._state.set_settings(
            settings.with_(clip=ClipRegion(tuple(planes), settings.clip.box, settings.clip.cap))
        )
        self.update()

    def _hover_plane(self, pos: QPoint) -> bool:
        """Light the plane handle under `pos`; whether there is one."""
        view = self._plane_view()
        kind = None if view is None else plane_handle_at(*view, pos.x() + 0.5, pos.y() + 0.5)
        if kind != self._hot_plane_handle:
            self._hot_plane_handle = kind
            self.update()
        if kind is not None:
            self.setCursor(QCursor(Qt.OpenHandCursor))
        return kind is not None

    def _face_drag_at(self, pos: QPoint) -> FaceDrag | None:
        """The drag a press at `pos` would start: a handle there that is not seen end-on."""
        view, volume = self._handle_view(), self._state.volume
        if view is None or volume is None:
            return None
        face = handle_at(*view, pos.x() + 0.5, pos.y() + 0.5)  # the pixel's centre, as the overlays
        if face is None:
            return None
        return FaceDrag.start(*view, face, volume.bounds, minimum_thickness(volume))

    def _set_hot_face(self, face: int | None, drag: FaceDrag | None) -> None:
        """Light `face`'s handle (None: none) with a size cursor along `drag`'s axis."""
        if drag is not None:
            self.setCursor(QCursor(_SIZE_CURSORS[drag.cursor_kind()]))
        else:
            self.unsetCursor()
        if face != self._hot_face:
            self._hot_face = face
            self.update()

    def _hover(self, pos: QPoint) -> None:
        drag = self._face_drag_at(pos)
        self._set_hot_face(None if drag is None else drag.face, drag)

    def _start_face_drag(self, pos: QPoint) -> bool:
        drag = self._face_drag_at(pos)
        if drag is None:
            return False
        self._face_drag = drag
        self._face_drag_from = pos
        self._drag_button = Qt.LeftButton
        self._set_hot_face(drag.face, drag)
        self._state.begin_interaction()
        return True

    def _drag_face(self, pos: QPoint) -> None:
        """Move the dragged face for the mouse's motion since the press."""
        drag = self._face_drag
        assert drag is not None
        if self._state.volume is None or tuple(self._state.volume.bounds) != drag.limits:
            return  # another volume came in mid-drag: the box belongs to the old one
        box = drag.box_for(pos.x() - self._face_drag_from.x(), pos.y() - self._face_drag_from.y())
        try:
            self._state.set_crop(box)
        except VolrenError:
            return  # a box with nothing in it (no whole tetrahedron of a mesh): keep the last one
        self.update()  # the handles follow now; the frame follows when it is rendered

    def leaveEvent(self, event: QEvent) -> None:
        if self._face_drag is None:
            self._set_hot_face(None, None)
        super().leaveEvent(event)

    def resizeEvent(self, event: QResizeEvent) -> None:
        super().resizeEvent(event)
        self.resized.emit()

    # ------------------------------------------------------------------ gestures
    def mousePressEvent(self, event: QMouseEvent) -> None:
        if event.button() == Qt.LeftButton and event.modifiers() & Qt.ControlModifier:
            self._pick(event.pos())
            event.accept()
            return
        plain_left = event.button() == Qt.LeftButton and not event.modifiers() & Qt.ShiftModifier
        if self._drag_button is None and plain_left and self._start_plane_drag(event.pos()):
            event.accept()
            return
        if self._drag_button is None and plain_left and self._start_face_drag(event.pos()):
            event.accept()
            return
        gesture = _GESTURES.get(event.button())
        if self._drag_button is not None or gesture is None or self._state.camera is None:
            return super().mousePressEvent(event)
        if gesture == "rotate" and event.modifiers() & Qt.ShiftModifier:
            gesture = "pan"
        self._drag_button = event.button()
        self._drag_gesture = gesture
        self._last_pos = event.pos()
        self._state.begin_interaction()
        event.accept()

    def mouseMoveEvent(self, event: QMouseEvent) -> None:
        if self._plane_drag is not None:
            self._drag_plane(event.pos(), bool(event.modifiers() & Qt.ShiftModifier))
            event.accept()
            return
        if self._face_drag is not None:
            self._drag_face(event.pos())
            event.accept()
            return
        if self._drag_gesture is None:
            if self._drag_button is None and not (
                self.clip_plane is not None and self._hover_plane(event.pos())
            ):
                if self.crop_handles:
                    self._hover(event.pos())
                elif self.clip_plane is not None:
                    self.unsetCursor()
            return super().mouseMoveEvent(event)
        pos = event.pos()
        dx, dy = pos.x() - self._last_pos.x(), pos.y() - self._last_pos.y()
        self._last_pos = pos
        if dx or dy:
            self._apply(self._drag_gesture, dx, dy)
        event.accept()

    def mouseReleaseEvent(self, event: QMouseEvent) -> None:
        if self._drag_button is None or event.button() != self._drag_button:
            return super().mouseReleaseEvent(event)
        self._drag_button = None
        self._drag_gesture = None
        dragged_face = self._face_drag is not None
        self._face_drag = None
        if self._plane_drag is not None:
            self._plane_drag = None
            self.unsetCursor()
        self._state.end_interaction()
        if dragged_face or self.crop_handles:
            self._hover(event.pos())
        event.accept()

    def wheelEvent(self, event: QWheelEvent) -> None:
        cam, volume = self._state.camera, self._state.volume
        delta = event.angleDelta().y()
        if cam is None or volume is None or delta == 0:
            return super().wheelEvent(event)
        with self._state.interaction():
            self._state.set_camera(
                interaction.dolly(cam, interaction.wheel_dolly_factor(delta), volume.bounds)
            )
        event.accept()

    def keyPressEvent(self, event: QKeyEvent) -> None:
        # Reached only when the window's 'R' shortcut did not take the key (e.g. window not active).
        if event.key() == Qt.Key_R and event.modifiers() in (Qt.NoModifier, Qt.KeypadModifier):
            self.resetRequested.emit()
            event.accept()
            return
        super().keyPressEvent(event)

    def _pick(self, pos: QPoint) -> None:
        """Emit pointPicked with the pixel under `pos` in `pixel_size()` coordinates (full frames)."""
        ratio = self.devicePixelRatioF()
        width, height = self.pixel_size()
        x = math.floor((pos.x() + 0.5) * ratio)
        y = math.floor((pos.y() + 0.5) * ratio)
        if 0 <= x < width and 0 <= y < height:
            self.pointPicked.emit(x, y)

    def _apply(self, gesture: str, dx: int, dy: int) -> None:
        cam, volume = self._state.camera, self._state.volume
        if cam is None or volume is None:
            return
        w, h = max(self.width(), 1), max(self.height(), 1)
        if gesture == "rotate":
            cam = interaction.rotate(cam, dx, dy, w, h, volume.bounds)
        elif gesture == "dolly":
            cam = interaction.dolly(cam, interaction.drag_dolly_factor(dy, h), volume.bounds)
        else:
            cam = interaction.pan(cam, dx, dy, h, volume.bounds)
        self._state.set_camera(cam)
