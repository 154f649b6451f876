"""Number controls that edit the state: gestures as interactions, and one render-settings field.

Dragging a slider or holding a spin box arrow sends a stream of values. Each is applied at once,
but inside `state.begin_interaction()` ... `end_interaction()`, so the app answers with cheap
previews and renders one full-quality frame when the control is let go. The interaction begins
only at the first value that actually changes: pressing and releasing without an edit (a click
that only focuses the control) asks for no frame at all. A typed value is a plain change.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtGui import QMouseEvent, QWheelEvent
from PyQt5.QtWidgets import QDoubleSpinBox, QHBoxLayout, QSlider, QWidget

from volren.app.core.state import ViewState
from volren.app.panels.base import signals_blocked


class Gesture:
    """One press ... release of a control, applied to the state as one interaction."""

    def __init__(self, state: ViewState) -> None:
        self._state = state
        self._held = False
        self._begun = False

    @property
    def held(self) -> bool:
        return self._held

    def press(self) -> None:
        self._held = True

    def release(self) -> None:
        self._held = False
        if self._begun:
            self._begun = False
            self._state.end_interaction()

    def apply(self, edit: Callable[[], None]) -> None:
        """Run `edit` (which changes the state): as a preview while the control is held."""
        if self._held and not self._begun:
            self._state.begin_interaction()
            self._begun = True
        edit()

    def attach_slider(self, slider: QSlider) -> None:
        slider.sliderPressed.connect(self.press)
        slider.sliderReleased.connect(self.release)

    def attach_spin_box(self, spin: GestureSpinBox) -> None:
        spin.gestureStarted.connect(self.press)
        spin.gestureEnded.connect(self.release)


class GestureSpinBox(QDoubleSpinBox):
    """A spin box that says when the mouse holds it (arrow auto-repeat) or a wheel turn steps it.

    Typed text is applied only when it is finished (Enter or leaving the field), not per key.
    """

    gestureStarted = pyqtSignal()
    gestureEnded = pyqtSignal()

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setKeyboardTracking(False)

    def mousePressEvent(self, event: QMouseEvent) -> None:
        self.gestureStarted.emit()
        super().mousePressEvent(event)

    def mouseReleaseEvent(self, event: QMouseEvent) -> None:
        super().mouseReleaseEvent(event)
        self.gestureEnded.emit()

    def wheelEvent(self, event: QWheelEvent) -> None:
        self.gestureStarted.emit()
        try:
            super().wheelEvent(event)
        finally:
            self.gestureEnded.emit()


def set_range_showing(spin: QDoubleSpinBox, minimum: float, maximum: float, value: float) -> None:
    """Give `spin` the range [minimum, maximum], widened to include `value` so that a value from a
    scene file outside the usual range is shown as it is, not clamped (signals blocked)."""
    with signals_blocked(spin):
        spin.setRange(min(minimum, value), max(maximum, value))
        spin.setValue(value)


class SettingControl(QWidget):
    """Edits one number field of the state's `RenderSettings`: a spin box, optionally a slider.

    The slider moves in steps of `step` from `minimum`; the spin box takes any value in range.
    """

    def __init__(
        self,
        state: ViewState,
        field: str,
        minimum: float,
        maximum: float,
        step: float,
        decimals: int,
        tooltip: str = "",
        slider: bool = True,
        parent: QWidget | None = None,
    ) -> None:
        super().__init__(parent)
        self._state = state
        self.field = field
        self._minimum, self._maximum, self._step = minimum, maximum, step
        self._gesture = Gesture(state)

        self.spin = GestureSpinBox(self)
        self.spin.setDecimals(decimals)
        self.spin.setSingleStep(step)
        self.spin.setRange(minimum, maximum)
        self._gesture.attach_spin_box(self.spin)
        self.spin.valueChanged.connect(self._on_spin)

        self.slider: QSlider | None = None
        layout = QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        if slider:
            self.slider = QSlider(Qt.Horizontal, self)
            self.slider.setRange(0, round((maximum - minimum) / step))
            self._gesture.attach_slider(self.slider)
            self.slider.valueChanged.connect(self._on_slider)
            layout.addWidget(self.slider, 1)
        layout.addWidget(self.spin)
        self.setToolTip(tooltip)
        self.refresh()

    def value(self) -> float:
        return float(getattr(self._state.settings, self.field))

    def refresh(self) -> None:
        """Show the state's value (signals blocked)."""
        value = self.value()
        set_range_showing(self.spin, self._minimum, self._maximum, value)
        self._show_on_slider(value)

    def _show_on_slider(self, value: float) -> None:
        if self.slider is not None:
            with signals_blocked(self.slider):
                self.slider.setValue(round((value - self._minimum) / self._step))

    def _on_slider(self, tick: int) -> None:
        value = self._minimum + tick * self._step
        with signals_blocked(self.spin):
            self.spin.setValue(value)
        self._commit(self.spin.value())

    def _on_spin(self, value: float) -> None:
        self._show_on_slider(value)
        self._commit(value)

    def _commit(self, value: float) -> None:
        if math.isclose(value, self.value(), rel_tol=0.0, abs_tol=1e-12):
            return
        state = self._state
        self._gesture.apply(lambda: state.set_settings(state.settings.with_(**{self.field: value})))
