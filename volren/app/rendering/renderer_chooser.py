"""The renderer chooser: a combo box that lists every renderer, disabling those that cannot draw.

Disabled entries stay visible with the reason as tooltip, so people learn why a renderer is not
offered (wrong volume kind, a plugin that failed to import) instead of wondering where it went.
"""

from __future__ import annotations

from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtGui import QStandardItemModel
from PyQt5.QtWidgets import QComboBox, QWidget

from volren.app.core.renderer_choice import RendererOption


class RendererChooser(QComboBox):
    """Emits `rendererChosen(name)` when the person picks an enabled renderer."""

    rendererChosen = pyqtSignal(str)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setSizeAdjustPolicy(QComboBox.AdjustToContents)
        self.setToolTip("Renderer")
        self.activated.connect(self._on_activated)

    def set_options(self, options: list[RendererOption], current: str | None) -> None:
        """Replace the entries; `current` is selected without emitting `rendererChosen`."""
        self.blockSignals(True)
        try:
            self.clear()
            model = self.model()
            assert isinstance(model, QStandardItemModel)
            for i, option in enumerate(options):
                self.addItem(option.name)
                item = model.item(i)
                item.setEnabled(option.enabled)
                self.setItemData(i, option.reason or option.name, Qt.ToolTipRole)
        finally:
            self.blockSignals(False)
        self.set_current(current)

    def set_current(self, name: str | None) -> None:
        self.blockSignals(True)
        try:
            self.setCurrentIndex(self.findText(name) if name else -1)
        finally:
            self.blockSignals(False)

    def names(self) -> list[str]:
        return [self.itemText(i) for i in range(self.count())]

    def is_enabled(self, name: str) -> bool:
        model = self.model()
        i = self.findText(name)
        return i >= 0 and isinstance(model, QStandardItemModel) and model.item(i).isEnabled()

    def tooltip(self, name: str) -> str | None:
        i = self.findText(name)
        return None if i < 0 else self.itemData(i, Qt.ToolTipRole)

    def _on_activated(self, index: int) -> None:
        name = self.itemText(index)
        if self.is_enabled(name):
            self.rendererChosen.emit(name)
