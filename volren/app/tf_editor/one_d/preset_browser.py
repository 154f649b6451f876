"""The colour-map browser: every colour map (volren's curated ones, then ParaView's), searchable.

Why: the combo box holds the ten curated maps; ParaView users know its catalogue (well over a
hundred ramps) by name and look for one by typing part of it, as in ParaView's preset dialog.
Typing filters the list by name (a case-insensitive substring); each row shows the map as a swatch
beside its name. Double-click or OK chooses the map, Cancel or Escape chooses nothing: the dialog
only reports the choice (`chosen()`), the editor applies it.

Swatches are drawn by the list's delegate when a row is first painted and kept by name, so
opening the dialog draws only the rows in view, not a few hundred images.
"""

from __future__ import annotations

import numpy as np
from PyQt5.QtCore import QModelIndex, QSize, Qt
from PyQt5.QtGui import QIcon, QImage, QPixmap
from PyQt5.QtWidgets import (
    QAbstractItemView,
    QDialog,
    QDialogButtonBox,
    QLabel,
    QLineEdit,
    QListWidget,
    QListWidgetItem,
    QStyledItemDelegate,
    QStyleOptionViewItem,
    QVBoxLayout,
    QWidget,
)

from volren.app.core.colormap_presets import all_preset_names, preset_source, unit_stops

#: Swatch size in the list (px).
SWATCH = QSize(96, 14)


def swatch_image(name: str, width: int = SWATCH.width(), height: int = SWATCH.height()) -> QImage:
    """The map's colours left to right, each column sampled at its centre, as the TF would."""
    stops = unit_stops(name)
    x = (np.arange(width) + 0.5) / width
    rgb = np.stack([np.interp(x, stops[:, 0], stops[:, c]) for c in (1, 2, 3)], axis=-1)
    row = np.round(np.clip(rgb, 0.0, 1.0) * 255).astype(np.uint8)
    pixels = np.ascontiguousarray(np.repeat(row[None], height, axis=0))
    return QImage(pixels.data, width, height, 3 * width, QImage.Format_RGB888).copy()


class SwatchDelegate(QStyledItemDelegate):
    """Gives each row its map's swatch as the row's icon, drawn the first time the row paints."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.icons: dict[str, QIcon] = {}

    def icon(self, name: str) -> QIcon:
        icon = self.icons.get(name)
        if icon is None:
            icon = self.icons[name] = QIcon(QPixmap.fromImage(swatch_image(name)))
        return icon

    def initStyleOption(self, option: QStyleOptionViewItem, index: QModelIndex) -> None:
        super().initStyleOption(option, index)
        option.icon = self.icon(index.data(Qt.DisplayRole))
        option.decorationSize = SWATCH
        option.features |= QStyleOptionViewItem.HasDecoration


class PresetBrowser(QDialog):
    """Search field, list of colour maps with swatches, OK and Cancel."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle("Colour maps")
        self.search = QLineEdit(self)
        self.search.setPlaceholderText("Search by name")
        self.search.setClearButtonEnabled(True)
        self.search.textChanged.connect(self.set_filter)
        self.list = QListWidget(self)
        self.list.setSelectionMode(QAbstractItemView.SingleSelection)
        self.list.setUniformItemSizes(True)
        self.list.setIconSize(SWATCH)
        self.delegate = SwatchDelegate(self.list)
        self.list.setItemDelegate(self.delegate)
        for name in all_preset_names():
            item = QListWidgetItem(name, self.list)
            item.setToolTip(
                "volren's curated maps"
                if preset_source(name) == "volren"
                else "ParaView (Kitware, BSD licence)"
            )
        self.count_label = QLabel(self)
        self.buttons = QDialogButtonBox(QDialogButtonBox.Ok | QDialogButtonBox.Cancel, self)
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        self.list.itemDoubleClicked.connect(lambda _item: self.accept())
        self.list.itemSelectionChanged.connect(self._update_ok)  # after the current item changed
        layout = QVBoxLayout(self)
        layout.addWidget(self.search)
        layout.addWidget(self.list, 1)
        layout.addWidget(self.count_label)
        layout.addWidget(self.buttons)
        self.resize(380, 480)
        self.reset()

    def reset(self) -> None:
        """Ready to choose again: no search text, nothing chosen, the list at the top."""
        self.search.clear()
        self.set_filter("")
        self.list.setCurrentRow(-1)
        self.list.scrollToTop()
        self._update_ok()

    def set_filter(self, text: str) -> None:
        """Show the maps whose names contain `text` (case ignored); a hidden choice is dropped."""
        needle = text.strip().casefold()
        for row in range(self.list.count()):
            item = self.list.item(row)
            item.setHidden(needle not in item.text().casefold())
        current = self.list.currentItem()
        if current is not None and current.isHidden():
            self.list.setCurrentRow(-1)
        shown = len(self.visible_names())
        self.count_label.setText(f"{shown} of {self.list.count()} colour maps")
        self._update_ok()

    def visible_names(self) -> list[str]:
        """The names the list shows now, in order."""
        return [
            self.list.item(r).text() for r in range(self.list.count()) if not self.list.item(r).isHidden()
        ]

    def item(self, name: str) -> QListWidgetItem:
        """The row of `name` (for scripted clicks)."""
        found = self.list.findItems(name, Qt.MatchExactly)
        if not found:
            raise KeyError(name)
        return found[0]

    def chosen(self) -> str | None:
        """The selected map's name, if it is shown."""
        item = self.list.currentItem()
        return None if item is None or item.isHidden() or not item.isSelected() else item.text()

    def accept(self) -> None:
        if self.chosen() is not None:  # OK without a choice (Enter in the search field) waits
            super().accept()

    def _update_ok(self) -> None:
        self.buttons.button(QDialogButtonBox.Ok).setEnabled(self.chosen() is not None)
