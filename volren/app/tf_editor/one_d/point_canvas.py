"""`PointCanvas`: the editing gestures the 1D TF editor's two canvases share.

The opacity curve and the colour bar both edit a sorted list of TF control points along one
`ValueAxis`: left-click on empty space adds a point and may drag it on, left-drag moves a point
between its neighbours, right-click or Delete removes it (never the first or last: they span the
TF's range), and a drag is one `begin_interaction`/`end_interaction` (cheap previews, one undo
step). Subclasses say which points they edit and how pixels map to them.

Two axes: `axis` is the value range shown (pixels <-> values), `limits` the range points may be
moved or typed into (the TF's and the data's). They differ while the view is zoomed in: the mouse
wheel asks for a zoom about the value under the cursor (`zoomRequested`, which the editor applies
to both canvases), and a point outside the view is neither lost nor pulled into it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from PyQt5.QtCore import QPointF, Qt, pyqtSignal
from PyQt5.QtGui import QHideEvent, QKeyEvent, QMouseEvent, QWheelEvent
from PyQt5.QtWidgets import QWidget

from volren.app.core.state import ViewState
from volren.model.transfer_function import TransferFunction1D

#: Horizontal room at both ends of the axis (px): a marker or point at the end stays whole.
MARGIN = 8
#: How close (px) a click must be to a stop or point to pick it rather than add a new one.
PICK_RADIUS = 6
#: The view's span is multiplied by this per wheel notch (120 eighths of a degree) towards you.
ZOOM_STEP = 0.8
#: The narrowest view, as a fraction of the limits' span (further zoom does nothing).
MIN_ZOOM = 1e-4


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
        return MARGIN + (value - self.lo) / (self.hi - self.lo) * axis_span(width)

    def to_value(self, x: Any, width: int) -> Any:
        """The data value at widget x (a number or an array)."""
        return self.lo + (x - MARGIN) / axis_span(width) * (self.hi - self.lo)

    def clamp(self, value: float, lo: float | None = None, hi: float | None = None) -> float:
        """`value` inside the axis and inside [lo, hi] where given (a point's neighbours)."""
        low = self.lo if lo is None else max(lo, self.lo)
        high = self.hi if hi is None else min(hi, self.hi)
        return float(min(max(value, low), max(low, high)))

    def zoomed(self, center: float, factor: float, limits: ValueAxis) -> ValueAxis | None:
        """This view scaled by `factor` about `center` (which stays where it is on screen), kept
        inside `limits` (slid back in at an edge); None when it would cover the limits whole
        (the unzoomed view). Never narrower than MIN_ZOOM of the limits."""
        span = (self.hi - self.lo) * factor
        full = limits.hi - limits.lo
        if span >= full:
            return None
        span = max(span, MIN_ZOOM * full)
        t = (center - self.lo) / (self.hi - self.lo)
        lo = center - t * span
        lo = min(max(lo, limits.lo), limits.hi - span)
        return ValueAxis(float(lo), float(lo + span))

    def within(self, limits: ValueAxis) -> ValueAxis | None:
        """The part of this view inside `limits`; None if that is all of the limits or too thin
        to be a view (the limits changed under a zoom)."""
        lo, hi = max(self.lo, limits.lo), min(self.hi, limits.hi)
        if hi - lo < MIN_ZOOM * (limits.hi - limits.lo) or (lo, hi) == (limits.lo, limits.hi):
            return None
        return ValueAxis(lo, hi)


def axis_span(width: int) -> float:
    """Pixels between the two margins: the length of the value axis on screen."""
    return float(max(width - 2 * MARGIN, 1))


def neighbours(xs: np.ndarray, index: int) -> tuple[float | None, float | None]:
    """The x of the points left and right of `index` (None at the ends): a dragged point stays
    between them, so dragging never reorders points."""
    left = float(xs[index - 1]) if index > 0 else None
    right = float(xs[index + 1]) if index + 1 < len(xs) else None
    return left, right


class PointCanvas(QWidget):
    """A widget editing one list of the state's 1D TF points; see the module docstring."""

    #: The selected point changed (its index, or None): numeric entry follows it.
    selectionChanged = pyqtSignal(object)
    #: The wheel asks to zoom the view: (the value under the cursor, the span's factor).
    zoomRequested = pyqtSignal(float, float)

    def __init__(self, state: ViewState, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._state = state
        self._axis = ValueAxis(0.0, 1.0)
        self._limits = self._axis
        self._drag: int | None = None
        self._selected: int | None = None
        self.setFocusPolicy(Qt.StrongFocus)

    @property
    def selected(self) -> int | None:
        """Index of the selected point (Delete removes it), or None."""
        return self._selected

    @selected.setter
    def selected(self, index: int | None) -> None:
        if index != self._selected:
            self._selected = index
            self.selectionChanged.emit(index)

    # ------------------------------------------------------------------ what subclasses supply
    def _points(self, tf: TransferFunction1D) -> NDArray[np.float64]:
        """The edited points (a copy), sorted by value in column 0."""
        raise NotImplementedError

    def _set_points(self, tf: TransferFunction1D, points: NDArray[np.float64]) -> None:
        raise NotImplementedError

    def _pick(self, pos: QPointF) -> int | None:
        """The point under `pos` (within PICK_RADIUS), or None."""
        raise NotImplementedError

    def _add_at(self, pos: QPointF) -> int:
        """Add a point for a click at `pos`; returns its index."""
        raise NotImplementedError

    def _move(self, index: int, pos: QPointF) -> None:
        """Move point `index` towards `pos` (between its neighbours)."""
        raise NotImplementedError

    # ------------------------------------------------------------------ model access
    def transfer_function(self) -> TransferFunction1D | None:
        tf = self._state.transfer_function
        return tf if isinstance(tf, TransferFunction1D) else None

    @property
    def axis(self) -> ValueAxis:
        """The values shown, left margin to right margin."""
        return self._axis

    @property
    def limits(self) -> ValueAxis:
        """Where points may go: the axis unless the view is zoomed in."""
        return self._limits

    def set_axis(self, axis: ValueAxis, limits: ValueAxis | None = None) -> None:
        self._axis = axis
        self._limits = axis if limits is None else limits
        self.update()

    def value_at(self, x: float) -> float:
        return self._axis.to_value(x, self.width())

    def model_changed(self) -> None:
        """The TF changed or was replaced: forget a selection that no longer exists."""
        tf = self.transfer_function()
        if tf is None or (self.selected is not None and self.selected >= len(self._points(tf))):
            self.selected = None
        self.update()

    def delete_selected(self) -> bool:
        """Remove the selected point unless it is the first or the last; True if removed."""
        tf = self.transfer_function()
        if tf is None or self.selected is None:
            return False
        points = self._points(tf)
        if not 0 < self.selected < len(points) - 1:
            return False
        index, self.selected = self.selected, None
        self._set_points(tf, np.delete(points, index, axis=0))
        return True

    # ------------------------------------------------------------------ mouse and keys
    def mousePressEvent(self, event: QMouseEvent) -> None:
        if self.transfer_function() is None:
            return
        pos = event.localPos()
        hit = self._pick(pos)
        if event.button() == Qt.RightButton:
            if hit is not None:
                self.selected = hit
                self.delete_selected()
            return
        if event.button() != Qt.LeftButton:
            return
        self._state.begin_interaction()
        self._drag = hit if hit is not None else self._add_at(pos)
        self.selected = self._drag
        self.update()

    def mouseMoveEvent(self, event: QMouseEvent) -> None:
        if self._drag is not None:
            self._move(self._drag, event.localPos())

    def mouseReleaseEvent(self, event: QMouseEvent) -> None:
        if event.button() == Qt.LeftButton:
            self._end_drag()

    def _end_drag(self) -> None:
        if self._drag is not None:
            self._drag = None
            self._state.end_interaction()

    def wheelEvent(self, event: QWheelEvent) -> None:
        notches = event.angleDelta().y() / 120
        if not notches or self.transfer_function() is None or self._drag is not None:
            return super().wheelEvent(event)
        self.zoomRequested.emit(self.value_at(event.position().x()), ZOOM_STEP**notches)
        event.accept()

    def keyPressEvent(self, event: QKeyEvent) -> None:
        if event.key() in (Qt.Key_Delete, Qt.Key_Backspace) and self.delete_selected():
            return
        super().keyPressEvent(event)

    def hideEvent(self, event: QHideEvent) -> None:
        self._end_drag()  # a drag cut short must not leave the state "interacting"
        super().hideEvent(event)
