"""The 2D transfer-function editor: widgets over the value x gradient-magnitude joint histogram.

Why: a 2D TF separates materials from the boundaries between them, which a 1D TF cannot (book
chapter 10); the joint histogram behind the widgets shows where those are (blobs and arches).

The editor follows the `ViewState`: it shows `state.transfer_function` when that is 2D and edits
that object in place (the state announces each edit, `TFHistory` makes it undoable); when the
state gets another TF object (undo, a file opened, a new volume) it simply shows the new one. It
never keeps a copy of the TF, so there is nothing to get out of step, and syncing its controls
never writes back (their signals are blocked meanwhile). With a 1D TF it offers to start a 2D one
over the volume's value range and robust gradient range (`core.joint_histogram`) that draws what
the 1D TF draws (`core.tf_seeding`).

Dual-domain picking: the main window passes `core.picking.pick`'s (value, gradient magnitude) to
`place_widget_at`, which adds a small Gaussian there and selects it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtGui import QColor, QKeyEvent
from PyQt5.QtWidgets import (
    QColorDialog,
    QDoubleSpinBox,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QStackedWidget,
    QVBoxLayout,
    QWidget,
)

from volren.app.core import tf_widget_geometry as geometry
from volren.app.core.joint_histogram import joint_histogram, suggested_gradient_max
from volren.app.core.state import Change, ViewState
from volren.app.core.tf_seeding import seeded_2d
from volren.app.qt_subscription import subscribe_while_alive
from volren.app.tf_editor.two_d.widget_canvas import TFWidgetCanvas
from volren.errors import VolrenError
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TransferFunction2D

#: Colours new widgets take in turn.
PALETTE = (
    (1.0, 0.55, 0.2),
    (0.3, 0.7, 1.0),
    (0.45, 0.95, 0.4),
    (1.0, 0.4, 0.7),
    (0.95, 0.9, 0.45),
)
#: The peak opacity of a new widget.
DEFAULT_OPACITY = 0.5

_MESSAGE_1D = (
    "The transfer function is 1D. A 2D transfer function assigns colour and opacity over value and "
    "gradient magnitude, which separates the boundaries between materials from the materials."
)
_USE_2D_TIP = (
    "Switch to a 2D transfer function that draws what the 1D one draws (a band over every gradient magnitude)"
)
_MESSAGE_NO_VOLUME = "Open a volume to edit a 2D transfer function over its values and gradient magnitudes."


class TransferFunction2DEditor(QWidget):
    """Edits the state's 2D TF; offers to create one while the TF is 1D."""

    #: (title, one-line message) of every error.
    errorOccurred = pyqtSignal(str, str)

    def __init__(self, state: ViewState, parent: QWidget | None = None,
                 two_d_reason: Callable[[str], str | None] = lambda _kind: None) -> None:  # fmt: skip
        """`two_d_reason(kind)`: why no registered renderer can draw a 2D TF on such volumes (None: one can)."""
        super().__init__(parent)
        self._state = state
        self._two_d_reason = two_d_reason
        self._histogram_key: tuple | None = None
        self._pages = QStackedWidget(self)
        self._pages.addWidget(self._build_1d_page())
        self._pages.addWidget(self._build_2d_page())
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self._pages)
        self.canvas.selectionChanged.connect(lambda _index: self._sync_controls())
        self.canvas.errorOccurred.connect(self.errorOccurred)
        self._unsubscribe = subscribe_while_alive(state, self, "_on_change")
        self._refresh()

    # ------------------------------------------------------------------ construction
    def _build_1d_page(self) -> QWidget:
        page = QWidget(self)
        self.message_label = QLabel(_MESSAGE_1D, page)
        self.message_label.setWordWrap(True)
        self.use_2d_button = QPushButton("Use a 2D transfer function", page)
        self.use_2d_button.clicked.connect(self.use_2d_transfer_function)
        layout = QVBoxLayout(page)
        layout.addWidget(self.message_label)
        layout.addWidget(self.use_2d_button)
        layout.addStretch(1)
        return page

    def _build_2d_page(self) -> QWidget:
        page = QWidget(self)
        self.add_gaussian_button = QPushButton("Gaussian", page)
        self.add_triangle_button = QPushButton("Triangle", page)
        self.add_box_button = QPushButton("Box", page)
        for button, kind in (
            (self.add_gaussian_button, "gaussian"),
            (self.add_triangle_button, "triangle"),
            (self.add_box_button, "box"),
        ):
            button.setToolTip(f"Add a {kind} widget in the middle of the view")
            button.clicked.connect(lambda _checked=False, k=kind: self.add_widget(k))
        self.delete_button = QPushButton("Delete", page)
        self.delete_button.setToolTip("Remove the selected widget  [Delete]")
        self.delete_button.clicked.connect(self.delete_selected)
        adders = QHBoxLayout()
        adders.addWidget(QLabel("Add:", page))
        for button in (self.add_gaussian_button, self.add_triangle_button, self.add_box_button):
            adders.addWidget(button)
        adders.addStretch(1)

        self.canvas = TFWidgetCanvas(self._state, page)

        self.color_button = QPushButton("Colour…", page)
        self.color_button.setToolTip("The selected widget's colour")
        self.color_button.clicked.connect(self._pick_color)
        self.opacity_spin = QDoubleSpinBox(page)
        self.opacity_spin.setRange(0.0, 1.0)
        self.opacity_spin.setSingleStep(0.05)
        self.opacity_spin.setDecimals(3)
        self.opacity_spin.setKeyboardTracking(False)
        self.opacity_spin.setToolTip("The selected widget's peak opacity")
        self.opacity_spin.valueChanged.connect(self.set_selected_opacity)
        self.gradient_max_spin = QDoubleSpinBox(page)
        self.gradient_max_spin.setRange(1e-12, 1e15)
        self.gradient_max_spin.setKeyboardTracking(False)
        self.gradient_max_spin.setToolTip("The top of the gradient-magnitude axis (world units)")
        self.gradient_max_spin.valueChanged.connect(self.set_gradient_max)
        self.fit_gradient_button = QPushButton("Fit", page)
        self.fit_gradient_button.setToolTip("Gradient axis to the data's 99.5th percentile")
        self.fit_gradient_button.clicked.connect(self.fit_gradient_max)
        self.gradient_max_spin.setMaximumWidth(120)  # its range would size it for 16 digits
        self.gradient_max_spin.setMinimumWidth(60)
        properties = QHBoxLayout()
        properties.addWidget(self.color_button)
        properties.addWidget(QLabel("Opacity", page))
        properties.addWidget(self.opacity_spin)
        properties.addStretch(1)
        properties.addWidget(self.delete_button)
        gradient_axis = QHBoxLayout()  # a second row: the dock stays about 320 px wide
        gradient_axis.addWidget(QLabel("Gradient max", page))
        gradient_axis.addWidget(self.gradient_max_spin)
        gradient_axis.addWidget(self.fit_gradient_button)
        gradient_axis.addStretch(1)

        layout = QVBoxLayout(page)
        layout.setContentsMargins(4, 4, 4, 4)
        layout.addLayout(adders)
        layout.addWidget(self.canvas, 1)
        layout.addLayout(properties)
        layout.addLayout(gradient_axis)
        return page

    # ------------------------------------------------------------------ following the state
    @property
    def transfer_function(self) -> TransferFunction2D | None:
        """The state's TF when it is 2D (what this editor edits), else None."""
        tf = self._state.transfer_function
        return tf if isinstance(tf, TransferFunction2D) else None

    def _on_change(self, change: Change) -> None:
        if change.what in ("tf", "volume"):
            self._refresh()

    def _refresh(self) -> None:
        tf = self.transfer_function
        self._pages.setCurrentIndex(0 if tf is None else 1)
        volume = self._state.volume
        reason = self._two_d_reason(volume.kind) if volume is not None else None
        self.use_2d_button.setEnabled(volume is not None and reason is None)
        self.use_2d_button.setToolTip(reason or _USE_2D_TIP)
        self.message_label.setText(_MESSAGE_NO_VOLUME if volume is None else (f"{_MESSAGE_1D}\n\n{reason}." if reason
                                                                               else _MESSAGE_1D))  # fmt: skip
        self.canvas.set_transfer_function(tf)
        self._update_histogram(tf)
        self._sync_controls()

    def _update_histogram(self, tf: TransferFunction2D | None) -> None:
        """Recompute the background only when the volume or the TF's axes changed."""
        volume = self._state.volume
        key = None if tf is None or volume is None else (volume, tf.value_range, tf.gradient_range[1])
        if key == self._histogram_key:
            return
        self._histogram_key = key
        histogram = None
        if tf is not None and volume is not None:
            try:
                histogram = joint_histogram(
                    volume, gradient_max=tf.gradient_range[1], value_range=tf.value_range
                )
            except VolrenError as exc:
                self.errorOccurred.emit("Cannot compute the joint histogram", str(exc))
        self.canvas.set_histogram(histogram)

    def _sync_controls(self) -> None:
        """Controls show the TF and the selection, without writing back."""
        tf = self.transfer_function
        index = self.canvas.selected
        widget = tf.widgets[index] if tf is not None and index is not None else None
        for control in (self.color_button, self.opacity_spin, self.delete_button):
            control.setEnabled(widget is not None)
        if widget is not None:
            self.opacity_spin.blockSignals(True)
            self.opacity_spin.setValue(widget.opacity)
            self.opacity_spin.blockSignals(False)
            r, g, b = widget.color
            self.color_button.setStyleSheet(f"background-color: {QColor.fromRgbF(r, g, b).name()};")
        else:
            self.color_button.setStyleSheet("")
        if tf is not None:
            gmax = tf.gradient_range[1]
            decimals = min(12, max(0, 3 - math.floor(math.log10(gmax))))
            self.gradient_max_spin.blockSignals(True)
            self.gradient_max_spin.setDecimals(decimals)
            self.gradient_max_spin.setSingleStep(10.0 ** (math.floor(math.log10(gmax)) - 1))
            self.gradient_max_spin.setValue(gmax)
            self.gradient_max_spin.blockSignals(False)

    # ------------------------------------------------------------------ edits
    @property
    def selected_index(self) -> int | None:
        return self.canvas.selected

    def select(self, index: int | None) -> None:
        self.canvas.select(index)

    def _edit_selected(self, **changes: object) -> None:
        tf, index = self.transfer_function, self.canvas.selected
        if tf is None or index is None:
            return
        widget = tf.widgets[index]
        try:
            new = replace(widget, **changes)
        except VolrenError as exc:
            self.errorOccurred.emit("Cannot edit the widget", str(exc))
            return
        if new != widget:
            tf.replace_widget(index, new)

    def add_widget(self, kind: str) -> int | None:
        """Add a `kind` widget (gaussian, triangle, box) in the middle of the view and select it."""
        tf = self.transfer_function
        if tf is None:
            return None
        color = PALETTE[len(tf.widgets) % len(PALETTE)]
        index = tf.add_widget(
            geometry.new_widget(kind, tf.value_range, tf.gradient_range[1], color, DEFAULT_OPACITY)
        )
        self.canvas.select(index)
        return index

    def place_widget_at(self, value: float, gradient_magnitude: float) -> int | None:
        """Add a small Gaussian at (value, gradient magnitude), e.g. a picked point, and select it."""
        tf = self.transfer_function
        if tf is None:
            self.errorOccurred.emit(
                "Cannot place a widget", "the transfer function is 1D; use a 2D transfer function first"
            )
            return None
        if not (math.isfinite(value) and math.isfinite(gradient_magnitude)):
            self.errorOccurred.emit("Cannot place a widget", "the picked point has no finite value")
            return None
        color = PALETTE[len(tf.widgets) % len(PALETTE)]
        widget = geometry.placed_gaussian(
            value, gradient_magnitude, tf.value_range, tf.gradient_range[1], color, DEFAULT_OPACITY
        )
        index = tf.add_widget(widget)
        self.canvas.select(index)
        return index

    def delete_selected(self) -> None:
        self.canvas.delete_selected()

    def set_selected_opacity(self, opacity: float) -> None:
        self._edit_selected(opacity=float(opacity))

    def set_selected_color(self, rgb: tuple[float, float, float]) -> None:
        self._edit_selected(color=tuple(float(c) for c in rgb))

    def choose_color(self, initial: QColor) -> QColor | None:
        """Ask for a colour (None: cancelled); tests replace this method."""
        color = QColorDialog.getColor(initial, self, "Widget colour")
        return color if color.isValid() else None

    def _pick_color(self) -> None:
        tf, index = self.transfer_function, self.canvas.selected
        if tf is None or index is None:
            return
        r, g, b = tf.widgets[index].color
        chosen = self.choose_color(QColor.fromRgbF(r, g, b))
        if chosen is not None:
            self.set_selected_color((chosen.redF(), chosen.greenF(), chosen.blueF()))

    def set_gradient_max(self, gmax: float) -> None:
        tf = self.transfer_function
        if tf is None or not gmax > 0 or math.isclose(gmax, tf.gradient_range[1], rel_tol=1e-9):
            return
        tf.set_gradient_range(float(gmax))

    def fit_gradient_max(self) -> None:
        if self._state.volume is not None:
            self.set_gradient_max(suggested_gradient_max(self._state.volume))

    def use_2d_transfer_function(self) -> None:
        """Replace the 1D TF with a 2D one: the 2D TF this volume had before, or one seeded from
        the 1D TF (`seeded_2d`: what it drew, as one 1d widget over every gradient magnitude) over
        the volume's value and robust gradient ranges."""
        volume = self._state.volume
        if volume is None or self._two_d_reason(volume.kind) is not None:
            return
        previous = self._state.replaced_transfer_function(2)
        if previous is not None:
            self._state.set_transfer_function(previous)
            return
        lo, hi = volume.value_range
        if not hi > lo:
            lo, hi = lo - 0.5, hi + 0.5  # a constant volume still gets a usable value axis
        try:
            gmax = suggested_gradient_max(volume)
            old = self._state.transfer_function
            if isinstance(old, TransferFunction1D):
                tf = seeded_2d(old, (lo, hi), gmax)
            else:
                unit = old.opacity_unit_distance if old is not None else 1.0
                tf = TransferFunction2D(
                    (lo, hi), (0.0, gmax), [geometry.boundary_triangle((lo, hi), gmax)], unit
                )
        except VolrenError as exc:
            self.errorOccurred.emit("Cannot create a 2D transfer function", str(exc))
            return
        self._state.set_transfer_function(tf)

    def detach(self) -> None:
        """Stop following the state (also done when the widget is destroyed); safe to call twice."""
        self._unsubscribe()

    # ------------------------------------------------------------------ keys
    def keyPressEvent(self, event: QKeyEvent) -> None:
        if event.key() in (Qt.Key_Delete, Qt.Key_Backspace) and self.canvas.selected is not None:
            self.delete_selected()
            event.accept()
            return
        super().keyPressEvent(event)
