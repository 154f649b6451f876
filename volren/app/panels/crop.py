"""The crop panel: an axis-aligned box in world units, a min and a max spin box per axis.

The panel holds the box as exact floats (`box()`); the spin boxes only show it, rounded to their
decimals, so editing one side never moves the others by a rounding. A side at the end of its
range means the volume's exact bound. Cropping itself happens in the state (`model.crop`: whole
samples on grids, whole tetrahedra on meshes); a box that leaves nothing is reported through
`errorOccurred` and the controls go back to what the state holds.

While cropping is switched off the controls keep the last box, so switching it on again brings
that box back (ParaView's crop widget does the same).
"""

from __future__ import annotations

import math
from functools import partial

from PyQt5.QtCore import pyqtSignal
from PyQt5.QtWidgets import QCheckBox, QGridLayout, QLabel, QPushButton, QVBoxLayout, QWidget

from volren.app.core.state import ViewState
from volren.app.panels.base import StatePanel, signals_blocked
from volren.app.panels.controls import Gesture, GestureSpinBox
from volren.errors import VolrenError
from volren.model.crop import Box
from volren.model.volume import Volume

AXES = "xyz"
SPIN_TIP = (
    "{side} of the crop box along {axis}, in world units; grids keep the whole samples the box "
    "touches, meshes the tetrahedra wholly inside"
)
NO_VOLUME_TIP = "Load a volume to crop it"


def decimals_for(extent: float) -> int:
    """Enough decimals to move a side by a thousandth of the volume's extent."""
    if not extent > 0:
        return 2
    return min(8, max(2, math.ceil(-math.log10(extent / 1000.0))))


class CropPanel(StatePanel):
    """A checkbox that enables cropping, a min and a max per axis over the volume's bounds, and
    a reset button."""

    #: (title, one-line message) when the state refuses a box.
    errorOccurred = pyqtSignal(str, str)

    watches = frozenset({"crop", "volume"})

    def __init__(self, state: ViewState, parent: QWidget | None = None) -> None:
        super().__init__(state, parent)
        self._gesture = Gesture(state)
        self._volume: Volume | None = None  # the volume the controls are laid out for
        self._box: list[float] = [0.0, 1.0] * 3
        self.enable = QCheckBox("Enable cropping", self)
        self.enable.toggled.connect(self._on_enable)
        #: xmin, xmax, ymin, ymax, zmin, zmax (the order of a `Box`).
        self.spins: list[GestureSpinBox] = []
        grid = QGridLayout()
        grid.addWidget(QLabel("min", self), 0, 1)
        grid.addWidget(QLabel("max", self), 0, 2)
        for axis in range(3):
            grid.addWidget(QLabel(AXES[axis], self), axis + 1, 0)
            for side in range(2):
                spin = GestureSpinBox(self)
                spin.setToolTip(SPIN_TIP.format(side=("Lower", "Upper")[side], axis=AXES[axis]))
                spin.valueChanged.connect(partial(self._on_spin, 2 * axis + side))
                self._gesture.attach_spin_box(spin)
                grid.addWidget(spin, axis + 1, side + 1)
                self.spins.append(spin)
        self.reset_button = QPushButton("Reset", self)
        self.reset_button.setToolTip("Back to the whole volume")
        self.reset_button.clicked.connect(self.reset)
        layout = QVBoxLayout(self)
        layout.addWidget(self.enable)
        layout.addLayout(grid)
        layout.addWidget(self.reset_button)
        self.refresh()

    def box(self) -> Box | None:
        """The box the controls hold, or None while cropping is switched off."""
        return tuple(self._box) if self.enable.isChecked() else None  # type: ignore[return-value]

    def reset(self) -> None:
        """Back to the whole volume (cropping stays switched on, with the full box)."""
        if self.state.volume is None:
            return
        self._box = list(self.state.volume.bounds)
        self._show_box()
        self._apply()

    def refresh(self) -> None:
        volume, crop = self.state.volume, self.state.crop
        new_volume = volume is not self._volume
        if new_volume:
            self._volume = volume
            self._lay_out_for(volume)
        if crop is not None:
            self._box = list(crop)
        elif volume is not None and (new_volume or self.enable.isChecked()):
            self._box = list(volume.bounds)
        # else: cropping is off; the controls keep the last box for when it is switched on again
        with signals_blocked(self.enable):
            self.enable.setChecked(crop is not None or (self.enable.isChecked() and not new_volume))
        self._show_box()
        self._update_enabled()

    # ------------------------------------------------------------------ internals
    def _lay_out_for(self, volume: Volume | None) -> None:
        """Spin box ranges, decimals and steps for this volume's bounds."""
        if volume is None:
            return
        bounds = volume.bounds
        for i, spin in enumerate(self.spins):
            lo, hi = float(bounds[i - i % 2]), float(bounds[i - i % 2 + 1])
            axis = i // 2
            step = volume.spacing[axis] if volume.kind == "uniform" else (hi - lo) / 100.0
            with signals_blocked(spin):
                spin.setDecimals(decimals_for(hi - lo))
                spin.setRange(lo, hi)
                spin.setSingleStep(step if step > 0 else 1.0)

    def _show_box(self) -> None:
        for spin, value in zip(self.spins, self._box, strict=True):
            with signals_blocked(spin):
                spin.setValue(value)

    def _update_enabled(self) -> None:
        has_volume = self.state.volume is not None
        self.enable.setEnabled(has_volume)
        self.setToolTip("" if has_volume else NO_VOLUME_TIP)
        for widget in (*self.spins, self.reset_button):
            widget.setEnabled(has_volume and self.enable.isChecked())

    def _on_enable(self, _on: bool) -> None:
        self._update_enabled()
        self._apply()

    def _on_spin(self, index: int, value: float) -> None:
        volume = self.state.volume
        if volume is None:
            return
        spin, lo_index = self.spins[index], index - index % 2
        if value <= spin.minimum():  # the exact bound, not its rounding to the shown decimals
            value = float(volume.bounds[lo_index])
        elif value >= spin.maximum():
            value = float(volume.bounds[lo_index + 1])
        if index % 2 == 0:  # never min > max: the edited side stops at the other one
            value = min(value, self._box[index + 1])
        else:
            value = max(value, self._box[index - 1])
        self._box[index] = value
        with signals_blocked(spin):
            spin.setValue(value)
        self._apply()

    def _apply(self) -> None:
        box = self.box()
        try:
            self._gesture.apply(lambda: self.state.set_crop(box))
        except VolrenError as exc:
            self.errorOccurred.emit("Cropping", str(exc))
            self.refresh()
