"""The sampling panel: sample distance, pre-integration and jitter.

The step is relative (units of the smallest voxel spacing or the mean tetrahedron edge), so
one value means the same quality on any volume; the panel also shows what it is in world units
for the loaded volume.
"""

from __future__ import annotations

from PyQt5.QtWidgets import QCheckBox, QFormLayout, QLabel, QWidget

from volren.app.core.state import ViewState
from volren.app.panels.base import StatePanel, signals_blocked, unsupported
from volren.app.panels.controls import SettingControl
from volren.renderers.base import KindSupport

STEP_TIP = (
    "Distance between samples along a ray, in units of the smallest voxel spacing (uniform grids) or "
    "the mean tetrahedron edge (meshes): smaller is more accurate and slower"
)
PREINTEGRATION_TIP = (
    "Integrate the transfer function exactly between samples (pre-integration tables): "
    "no slicing artefacts with sharp transfer functions, even at large steps"
)
JITTER_TIP = "Start each ray at a random offset: trades wood-grain artefacts for fine noise"


class SamplingPanel(StatePanel):
    """Step (0.05..4) with its length in world units, pre-integration and jitter checkboxes."""

    watches = frozenset(
        {"settings", "volume", "renderer"}
    )  # a renderer switch brings its quality level's step

    def __init__(self, state: ViewState, parent: QWidget | None = None) -> None:
        super().__init__(state, parent)
        self._support: KindSupport | None = None
        self.step = SettingControl(state, "step", 0.05, 4.0, 0.05, 3, STEP_TIP, slider=False, parent=self)
        self.step_length = QLabel(self)
        self.step_length.setWordWrap(True)  # a long unit must not widen the dock after a load
        self.preintegration = QCheckBox("Pre-integration", self)
        self.preintegration.toggled.connect(lambda on: self._set_flag("preintegration", on))
        self.jitter = QCheckBox("Jitter", self)
        self.jitter.setToolTip(JITTER_TIP)
        self.jitter.toggled.connect(lambda on: self._set_flag("jitter", on))
        layout = QFormLayout(self)
        layout.addRow("Step", self.step)
        layout.addRow("", self.step_length)
        layout.addRow(self.preintegration)
        layout.addRow(self.jitter)
        self.refresh()

    def set_capabilities(self, support: KindSupport | None) -> None:
        """What the current renderer can do with the loaded volume (None: assume everything)."""
        self._support = support
        self.refresh()

    def refresh(self) -> None:
        settings = self.state.settings
        self.step.refresh()
        volume = self.state.volume
        unit = (
            "smallest voxel spacing"
            if volume is None or volume.kind == "uniform"
            else "mean tetrahedron edge"
        )
        length = f" = {settings.step * volume.characteristic_length:.4g} world units" if volume else ""
        self.step_length.setText(f"× {unit}{length}")
        with signals_blocked(self.preintegration, self.jitter):
            self.preintegration.setChecked(settings.preintegration)
            self.jitter.setChecked(settings.jitter)
        can_preintegrate = self._support is None or self._support.preintegration
        self.preintegration.setEnabled(can_preintegrate)
        self.preintegration.setToolTip(
            PREINTEGRATION_TIP if can_preintegrate else unsupported(self.state, "pre-integration")
        )

    def _set_flag(self, name: str, on: bool) -> None:
        if on != getattr(self.state.settings, name):
            self.state.set_settings(self.state.settings.with_(**{name: on}))
