"""The blend-mode panel: how the samples along a ray combine (composite, MIP, MinIP, average).

Modes the current renderer cannot draw stay listed but disabled, with the reason as tooltip (as
in the renderer chooser), so people learn they exist elsewhere. With a 2D transfer function only
the modes a renderer supports for 2D TFs are offered.
"""

from __future__ import annotations

from PyQt5.QtCore import Qt
from PyQt5.QtGui import QStandardItemModel
from PyQt5.QtWidgets import QComboBox, QFormLayout, QWidget

from volren.app.core.state import Change, ViewState
from volren.app.panels.base import StatePanel, signals_blocked, unsupported
from volren.model.settings import BlendMode
from volren.renderers.base import KindSupport

LABELS = {
    BlendMode.COMPOSITE: (
        "Composite",
        "Emission and absorption, front to back (the transfer function's colours)",
    ),
    BlendMode.MAXIMUM: ("Maximum intensity", "The largest value along each ray (MIP)"),
    BlendMode.MINIMUM: ("Minimum intensity", "The smallest value along each ray (MinIP)"),
    BlendMode.AVERAGE: ("Average intensity", "The mean value along each ray (like a radiograph)"),
}


class BlendPanel(StatePanel):
    """A combo box over `BlendMode`."""

    watches = frozenset({"settings", "tf", "volume"})

    def __init__(self, state: ViewState, parent: QWidget | None = None) -> None:
        super().__init__(state, parent)
        self._support: KindSupport | None = None
        self._shown_tf_dims = 1
        self.combo = QComboBox(self)
        self.combo.setSizeAdjustPolicy(QComboBox.AdjustToMinimumContentsLengthWithIcon)  # the dock is narrow
        self.combo.setMinimumContentsLength(10)
        for mode in BlendMode:
            self.combo.addItem(LABELS[mode][0], mode.value)
        self.combo.activated.connect(self._on_activated)
        layout = QFormLayout(self)
        layout.addRow("Blend mode", self.combo)
        self.refresh()

    def _on_change(self, change: Change) -> None:
        """A TF edit changes what is offered only when it changes the TF's dimension (2D TFs
        allow fewer modes): not on every edit of a drag."""
        tf = self.state.transfer_function
        dims = tf.dims if tf is not None else 1
        if change.what != "tf" or dims != self._shown_tf_dims:
            self._shown_tf_dims = dims
            super()._on_change(change)

    def set_capabilities(self, support: KindSupport | None) -> None:
        """What the current renderer can do with the loaded volume (None: assume everything)."""
        self._support = support
        self.refresh()

    def mode_enabled(self, mode: BlendMode) -> bool:
        model = self.combo.model()
        assert isinstance(model, QStandardItemModel)
        return model.item(self.combo.findData(mode.value)).isEnabled()

    def mode_tooltip(self, mode: BlendMode) -> str:
        return str(self.combo.itemData(self.combo.findData(mode.value), Qt.ToolTipRole))

    def refresh(self) -> None:
        model = self.combo.model()
        assert isinstance(model, QStandardItemModel)
        tf = self.state.transfer_function
        two_d = tf is not None and tf.dims == 2
        for i in range(self.combo.count()):
            mode = BlendMode(self.combo.itemData(i))
            reason = self._unsupported_reason(mode, two_d)
            model.item(i).setEnabled(reason is None)
            self.combo.setItemData(i, reason or LABELS[mode][1], Qt.ToolTipRole)
        with signals_blocked(self.combo):
            self.combo.setCurrentIndex(self.combo.findData(self.state.settings.blend_mode.value))

    def _unsupported_reason(self, mode: BlendMode, two_d: bool) -> str | None:
        support = self._support
        if support is None:
            return None
        if mode not in support.blend_modes:
            return unsupported(self.state, f"{mode} blend mode")
        if two_d and mode not in support.blend_modes_2d:
            return unsupported(self.state, f"{mode} blend mode with 2D transfer functions")
        return None

    def _on_activated(self, index: int) -> None:
        mode = BlendMode(self.combo.itemData(index))
        if mode != self.state.settings.blend_mode:
            self.state.set_settings(self.state.settings.with_(blend_mode=mode))
