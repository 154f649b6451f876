"""The lighting panel: shading on or off, and the Blinn-Phong coefficients of vtkVolumeProperty.

The coefficients are greyed out while shading is off (they change nothing then), and everything
is greyed out, with the reason as tooltip, when the current renderer cannot shade.
"""

from __future__ import annotations

from PyQt5.QtWidgets import QCheckBox, QFormLayout, QWidget

from volren.app.core.state import ViewState
from volren.app.panels.base import StatePanel, signals_blocked, unsupported
from volren.app.panels.controls import SettingControl
from volren.renderers.base import KindSupport

SHADE_TIP = "Blinn-Phong shading with a headlight; normals from the gradient of the data"
#: (field, minimum, maximum, step, decimals, tooltip) of each coefficient, vtkVolumeProperty's.
COEFFICIENTS = (
    ("ambient", 0.0, 1.0, 0.01, 2, "Light reflected whatever the surface's orientation"),
    ("diffuse", 0.0, 1.0, 0.01, 2, "Light scattered evenly, brightest where the surface faces the light"),
    ("specular", 0.0, 1.0, 0.01, 2, "Strength of the highlights"),
    ("specular_power", 1.0, 128.0, 1.0, 1, "Sharpness of the highlights (the Phong exponent)"),
)


class LightingPanel(StatePanel):
    """Shade checkbox; ambient, diffuse, specular (0..1) and specular power (1..128)."""

    watches = frozenset({"settings", "volume"})  # a load brings settings with the volume

    def __init__(self, state: ViewState, parent: QWidget | None = None) -> None:
        super().__init__(state, parent)
        self._support: KindSupport | None = None
        self.shade = QCheckBox("Shade", self)
        self.shade.toggled.connect(self._on_shade)
        controls = [SettingControl(state, *spec, parent=self) for spec in COEFFICIENTS]
        self.ambient, self.diffuse, self.specular, self.specular_power = controls
        layout = QFormLayout(self)
        layout.addRow(self.shade)
        for (field, *_), control in zip(COEFFICIENTS, controls, strict=True):
            layout.addRow(field.replace("_", " ").capitalize(), control)
        self.refresh()

    @property
    def coefficients(self) -> tuple[SettingControl, ...]:
        return (self.ambient, self.diffuse, self.specular, self.specular_power)

    def set_capabilities(self, support: KindSupport | None) -> None:
        """What the current renderer can do with the loaded volume (None: assume everything)."""
        self._support = support
        self.refresh()

    def refresh(self) -> None:
        settings = self.state.settings
        can_shade = self._support is None or self._support.shading
        with signals_blocked(self.shade):
            self.shade.setChecked(settings.shade)
        self.shade.setEnabled(can_shade)
        self.shade.setToolTip(SHADE_TIP if can_shade else unsupported(self.state, "shading"))
        for control in self.coefficients:
            control.refresh()
            control.setEnabled(can_shade and settings.shade)

    def _on_shade(self, on: bool) -> None:
        if on != self.state.settings.shade:
            self.state.set_settings(self.state.settings.with_(shade=on))
