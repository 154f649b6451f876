"""The clipping panel: up to six oblique planes, each keeping the side its normal points to.

The planes live in the state's settings (`RenderSettings.clip`, with the crop box kept apart in
the state), so they are saved in scenes, undone with the settings and drawn exactly by every
renderer that clips (rays cut at each plane: Real-Time Volume Graphics, section 15.1). A plane in
the list can be switched off without losing it, inverted, removed, turned to an axis or to the
view direction, and moved along its normal with a slider (previews while the slider is held, one
full frame at release, as every gesture). A renderer that cannot clip is replaced by one that can
when a plane is switched on, as for any setting (`RendererControl`).
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np
from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import (
    QCheckBox,
    QGridLayout,
    QHBoxLayout,
    QLabel,
    QListWidget,
    QListWidgetItem,
    QPushButton,
    QSlider,
    QVBoxLayout,
    QWidget,
)

from volren.app.core.plane_handles import extent_along
from volren.app.core.state import ViewState
from volren.app.panels.base import StatePanel, signals_blocked
from volren.app.panels.controls import Gesture, GestureSpinBox, set_range_showing
from volren.app.panels.crop import decimals_for
from volren.model.clip_region import MAX_PLANES, ClipPlane, ClipRegion

#: The axis buttons' width and the number fields' least width (pixels): the panel shares the
#: Rendering dock with the crop box and must fit its width.
NARROW_BUTTON = 36
SPIN_MIN_WIDTH = 40
#: Ticks of the position slider across the volume's extent along the normal.
POSITION_TICKS = 1000
AXIS_NORMALS = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}
NO_VOLUME_TIP = "Load a volume to clip it"


def plane_label(index: int, plane: ClipPlane) -> str:
    """ "Plane 1: normal (1, 0, 0), inverted" as the list shows it."""
    normal = ", ".join(f"{v:.3g}" for v in plane.normal)
    return f"Plane {index + 1}: normal ({normal}){', inverted' if plane.invert else ''}"


class ClippingPanel(StatePanel):
    """The list of clip planes with add, remove, invert, on/off, axis and view presets, the selected
    plane's point and normal, and its position along the normal."""

    watches = frozenset({"settings", "volume"})

    def __init__(self, state: ViewState, parent: QWidget | None = None) -> None:
        super().__init__(state, parent)
        self._gesture = Gesture(state)
        self.plane_list = QListWidget(self)
        self.plane_list.setMaximumHeight(110)
        self.plane_list.setToolTip("Clip planes: checked ones clip; each keeps the side its normal points to")
        self.plane_list.currentRowChanged.connect(lambda _row: self._show_selected())
        self.plane_list.itemChanged.connect(self._on_item_changed)
        self.add_button = QPushButton("Add", self)
        self.add_button.setToolTip("A plane through the volume's centre, facing away from the eye")
        self.add_button.clicked.connect(self.add_plane)
        self.remove_button = QPushButton("Remove", self)
        self.remove_button.clicked.connect(self.remove_plane)
        self.invert_button = QPushButton("Invert", self)
        self.invert_button.setToolTip("Keep the other side of the selected plane")
        self.invert_button.clicked.connect(self.invert_plane)
        buttons = QHBoxLayout()
        for button in (self.add_button, self.remove_button, self.invert_button):
            buttons.addWidget(button)
        self.axis_buttons: dict[str, QPushButton] = {}
        presets = QHBoxLayout()
        presets.addWidget(QLabel("Normal:", self))
        for name, normal in AXIS_NORMALS.items():
            button = QPushButton(name, self)
            button.setMaximumWidth(NARROW_BUTTON)
            button.setToolTip(f"Turn the selected plane to face +{name.lower()}")
            button.clicked.connect(partial(self.set_normal, normal))
            presets.addWidget(button)
            self.axis_buttons[name] = button
        self.view_button = QPushButton("View", self)
        self.view_button.setMaximumWidth(int(1.5 * NARROW_BUTTON))
        self.view_button.setToolTip("Turn the selected plane to face away from the eye (cut the near part)")
        self.view_button.clicked.connect(self.face_view)
        presets.addWidget(self.view_button)
        #: origin x, y, z then normal x, y, z of the selected plane
        self.spins: list[GestureSpinBox] = []
        grid = QGridLayout()
        for column, axis in enumerate("xyz"):
            grid.addWidget(QLabel(axis, self), 0, column + 1, alignment=Qt.AlignCenter)
        for row, what in enumerate(("Point", "Normal")):
            grid.addWidget(QLabel(what, self), row + 1, 0)
            for column in range(3):
                spin = GestureSpinBox(self)
                spin.setMinimumWidth(SPIN_MIN_WIDTH)  # the range sets the hint: six of them must fit ~260 px
                spin.setRange(-1.0, 1.0)
                spin.valueChanged.connect(self._on_spin)
                self._gesture.attach_spin_box(spin)
                grid.addWidget(spin, row + 1, column + 1)
                self.spins.append(spin)
        self.cap = QCheckBox("Cut faces", self)
        self.cap.setToolTip(
            "Draw where the planes and the crop box cut the volume as an opaque face in the TF's colour "
            "there, lit by the plane when shading is on"
        )
        self.cap.toggled.connect(self._on_cap)
        self.position = QSlider(Qt.Horizontal, self)
        self.position.setRange(0, POSITION_TICKS)
        self.position.setToolTip("Move the selected plane along its normal across the volume")
        self.position.valueChanged.connect(self._on_position)
        self._gesture.attach_slider(self.position)
        layout = QVBoxLayout(self)
        layout.addWidget(self.plane_list)
        layout.addLayout(buttons)
        layout.addLayout(presets)
        layout.addLayout(grid)
        row = QHBoxLayout()
        row.addWidget(QLabel("Position", self))
        row.addWidget(self.position, 1)
        layout.addLayout(row)
        layout.addWidget(self.cap)
        self.refresh()

    # ------------------------------------------------------------------ what the state holds
    @property
    def planes(self) -> tuple[ClipPlane, ...]:
        return self.state.settings.clip.planes

    def selected(self) -> int | None:
        row = self.plane_list.currentRow()
        return row if 0 <= row < len(self.planes) else None

    def refresh(self) -> None:
        with signals_blocked(self.cap):
            self.cap.setChecked(self.state.settings.clip.cap)
        self.cap.setEnabled(self.state.volume is not None)
        planes = self.planes
        row = self.plane_list.currentRow()
        with signals_blocked(self.plane_list):
            self.plane_list.clear()
            for i, plane in enumerate(planes):
                item = QListWidgetItem(plane_label(i, plane))
                item.setFlags(item.flags() | Qt.ItemIsUserCheckable)
                item.setCheckState(Qt.Checked if plane.enabled else Qt.Unchecked)
                self.plane_list.addItem(item)
            if planes:
                self.plane_list.setCurrentRow(min(max(row, 0), len(planes) - 1))
        self._show_selected()

    def _show_selected(self) -> None:
        volume, index = self.state.volume, self.selected()
        has_volume = volume is not None
        self.setToolTip("" if has_volume else NO_VOLUME_TIP)
        self.add_button.setEnabled(has_volume and len(self.planes) < MAX_PLANES)
        for widget in (self.remove_button, self.invert_button, self.view_button, *self.axis_buttons.values(),
                       *self.spins, self.position):  # fmt: skip
            widget.setEnabled(has_volume and index is not None)
        if index is None or volume is None:
            return
        plane = self.planes[index]
        extent = float(max(np.subtract(volume.bounds[1::2], volume.bounds[0::2])))
        decimals = decimals_for(extent)
        for axis, spin in enumerate(self.spins):
            value = (*plane.origin, *plane.normal)[axis]
            with signals_blocked(spin):
                spin.setDecimals(decimals if axis < 3 else 3)
                if axis < 3:  # a point within the volume's extent around it; a normal's components in [-1, 1]
                    lo, hi = float(volume.bounds[2 * axis]), float(volume.bounds[2 * axis + 1])
                    set_range_showing(spin, lo - extent, hi + extent, value)
                    spin.setSingleStep(extent / 100.0 or 1.0)
                else:
                    set_range_showing(spin, -1.0, 1.0, value)
                    spin.setSingleStep(0.05)
                spin.setValue(value)
        lo, hi = extent_along(volume.bounds, plane.normal)
        n = np.asarray(plane.normal) / np.linalg.norm(plane.normal)
        at = float(np.dot(plane.origin, n))
        with signals_blocked(self.position):
            self.position.setValue(round((at - lo) / (hi - lo) * POSITION_TICKS) if hi > lo else 0)

    # ------------------------------------------------------------------ edits
    def _set_planes(self, planes: tuple[ClipPlane, ...]) -> None:
        clip = ClipRegion(planes, self.state.settings.clip.box, self.state.settings.clip.cap)
        self._gesture.apply(lambda: self.state.set_settings(self.state.settings.with_(clip=clip)))

    def _replace(self, index: int, plane: ClipPlane) -> None:
        planes = list(self.planes)
        planes[index] = plane
        self._set_planes(tuple(planes))

    def add_plane(self) -> None:
        """A plane through the volume's centre facing away from the eye: it cuts the near half
        away, the view a person adding a plane wants to see into (ParaView's camera normal)."""
        volume = self.state.volume
        if volume is None or len(self.planes) >= MAX_PLANES:
            return
        centre = tuple((lo + hi) / 2 for lo, hi in zip(volume.bounds[0::2], volume.bounds[1::2], strict=True))
        camera = self.state.camera
        normal = tuple(camera.direction) if camera is not None else (1.0, 0.0, 0.0)
        self._set_planes((*self.planes, ClipPlane(centre, normal)))  # type: ignore[arg-type]
        self.plane_list.setCurrentRow(len(self.planes) - 1)

    def remove_plane(self) -> None:
        index = self.selected()
        if index is not None:
            self._set_planes(self.planes[:index] + self.planes[index + 1 :])

    def invert_plane(self) -> None:
        index = self.selected()
        if index is not None:
            plane = self.planes[index]
            self._replace(index, ClipPlane(plane.origin, plane.normal, not plane.invert, plane.enabled))

    def set_normal(self, normal: tuple[float, float, float]) -> None:
        index = self.selected()
        if index is not None:
            plane = self.planes[index]
            self._replace(index, ClipPlane(plane.origin, normal, plane.invert, plane.enabled))

    def face_view(self) -> None:
        camera = self.state.camera
        if camera is not None:
            self.set_normal(tuple(float(v) for v in camera.direction))  # type: ignore[arg-type]

    def _on_cap(self, on: bool) -> None:
        clip = self.state.settings.clip
        if on != clip.cap:
            self.state.set_settings(self.state.settings.with_(clip=ClipRegion(clip.planes, clip.box, on)))

    def _on_item_changed(self, item: QListWidgetItem) -> None:
        index = self.plane_list.row(item)
        if 0 <= index < len(self.planes):
            plane = self.planes[index]
            on = item.checkState() == Qt.Checked
            if on != plane.enabled:
                self._replace(index, ClipPlane(plane.origin, plane.normal, plane.invert, on))

    def _on_spin(self, _value: float) -> None:
        index = self.selected()
        if index is None:
            return
        values = [spin.value() for spin in self.spins]
        plane = self.planes[index]
        normal = tuple(values[3:])
        if not math.hypot(*normal) > 0:  # a zero normal is no plane: show the last good one
            self._show_selected()
            return
        self._replace(index, ClipPlane(tuple(values[:3]), normal, plane.invert, plane.enabled))  # type: ignore[arg-type]

    def _on_position(self, tick: int) -> None:
        """The plane moved along its normal to the slider's place across the volume."""
        volume, index = self.state.volume, self.selected()
        if volume is None or index is None:
            return
        plane = self.planes[index]
        lo, hi = extent_along(volume.bounds, plane.normal)
        n = np.asarray(plane.normal) / np.linalg.norm(plane.normal)
        origin = np.asarray(plane.origin, dtype=np.float64)
        target = lo + (hi - lo) * tick / POSITION_TICKS
        moved = origin + (target - float(origin @ n)) * n
        self._replace(index, ClipPlane(tuple(moved), plane.normal, plane.invert, plane.enabled))  # type: ignore[arg-type]
