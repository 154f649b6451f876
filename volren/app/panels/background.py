"""The background panel: one button that shows the viewport's background colour and changes it.

The colour dialog is opened through `choose_color` alone, so tests (and embedders with their own
colour picker) replace one method instead of a modal dialog.
"""

from __future__ import annotations

from PyQt5.QtGui import QColor, QIcon, QPixmap
from PyQt5.QtWidgets import QColorDialog, QFormLayout, QPushButton, QWidget

from volren.app.core.state import ViewState
from volren.app.panels.base import StatePanel, qcolor


class BackgroundPanel(StatePanel):
    """A colour button: the swatch and hex name of `state.background`; a click picks another."""

    watches = frozenset({"background"})

    def __init__(self, state: ViewState, parent: QWidget | None = None) -> None:
        super().__init__(state, parent)
        self.button = QPushButton(self)
        self.button.setToolTip("Colour behind the volume in the viewport and in screenshots")
        self.button.clicked.connect(self.pick)
        layout = QFormLayout(self)
        layout.addRow("Background", self.button)
        self.refresh()

    def choose_color(self, initial: QColor) -> QColor | None:
        """Ask for a colour starting from `initial`; None when the person cancels."""
        color = QColorDialog.getColor(initial, self, "Background colour")
        return color if color.isValid() else None

    def pick(self) -> None:
        """Let the person choose the background; an unchanged colour changes nothing."""
        current = qcolor(self.state.background)
        color = self.choose_color(current)
        if color is None or color.name() == current.name():
            return
        self.state.set_background((color.redF(), color.greenF(), color.blueF()))

    def refresh(self) -> None:
        color = qcolor(self.state.background)
        swatch = QPixmap(16, 16)
        swatch.fill(color)
        self.button.setIcon(QIcon(swatch))
        self.button.setText(color.name())
