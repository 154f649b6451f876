"""The Channels panel: one row per channel of a multi-channel volume (as napari's layer list and
OMERO's channel list show them).

Each row edits one channel of the `ChannelTransferFunction` (Max 1995, section 2: the channels'
extinctions and emissions add, a 1D TF each): shown or hidden, its colour (the colour of its whole
TF), its weight (a scale of its density). Selecting a row has the 1D TF editor edit that channel's
TF (`ViewState.select_channel`). Edits go through the channel TF's setters, so the frame follows
and undo records them like any TF edit. The colour dialog is opened through `choose_color` alone,
so tests replace one method instead of a modal dialog.
"""

from __future__ import annotations

import numpy as np
from PyQt5.QtCore import Qt
from PyQt5.QtGui import QColor, QIcon, QPixmap
from PyQt5.QtWidgets import (
    QCheckBox,
    QColorDialog,
    QDoubleSpinBox,
    QLabel,
    QPushButton,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from volren.app.core.state import ViewState
from volren.app.panels.base import StatePanel, qcolor, row_table, signals_blocked
from volren.model.transfer_function import TransferFunction1D

#: The largest weight offered: ten times a channel's density makes a faint channel solid.
MAX_WEIGHT = 10.0
COLUMNS = ("Show", "Colour", "Name", "Weight")
SHOW, COLOUR, NAME, WEIGHT = range(len(COLUMNS))
NO_CHANNELS = (
    "No channels: open an image of several channels (an OME-Zarr image with a c axis, an array of "
    "several components)"
)
TWO_D = "Channels are not mixed with a 2D transfer function: switch the editor to 1D to draw them"


def channel_color(tf: TransferFunction1D) -> tuple[float, float, float]:
    """The colour a channel's swatch shows: its TF's colour at the top of the TF's range (where a
    fluorescence ramp is brightest; the colour itself for a one-colour TF)."""
    rgb, _ = tf.sample(np.array([tf.value_range[1]]))
    return (float(rgb[0, 0]), float(rgb[0, 1]), float(rgb[0, 2]))


def recoloured(tf: TransferFunction1D, rgb: tuple[float, float, float]) -> TransferFunction1D:
    """A copy of `tf` drawn in the one colour `rgb` (its opacity kept)."""
    points = tf.color_points.copy()
    points[:, 1:] = rgb  # the same points, so the editor's colour bar keeps its stops
    out = tf.copy()
    out.set_color_points(points)
    return out


class ChannelsPanel(StatePanel):
    """The channels of the volume shown, a row each: Show, Colour, Name, Weight."""

    watches = frozenset({"volume", "tf"})

    def __init__(self, state: ViewState, parent: QWidget | None = None) -> None:
        super().__init__(state, parent)
        self.note = QLabel(self)
        self.note.setWordWrap(True)
        self.table = row_table(self, COLUMNS, NAME)
        self.table.currentCellChanged.connect(lambda row, *_: self.select(row))
        layout = QVBoxLayout(self)
        layout.setContentsMargins(2, 2, 2, 2)
        layout.addWidget(self.note)
        layout.addWidget(self.table)
        self._names: tuple[str, ...] = ()  # the channel of each row, by name
        self._channels: object = None  # the ChannelSet listed
        self.refresh()

    # ------------------------------------------------------------------ reading
    @property
    def count(self) -> int:
        return len(self._names)

    def name(self, channel: int) -> str:
        item = self.table.item(channel, NAME)
        assert item is not None
        return item.text()

    def show_box(self, channel: int) -> QCheckBox:
        widget = self.table.cellWidget(channel, SHOW)
        assert isinstance(widget, QCheckBox)
        return widget

    def color_button(self, channel: int) -> QPushButton:
        widget = self.table.cellWidget(channel, COLOUR)
        assert isinstance(widget, QPushButton)
        return widget

    def weight_box(self, channel: int) -> QDoubleSpinBox:
        widget = self.table.cellWidget(channel, WEIGHT)
        assert isinstance(widget, QDoubleSpinBox)
        return widget

    # ------------------------------------------------------------------ following the state
    def refresh(self) -> None:
        state = self.state
        channels, ctf = state.channels, state.channel_transfer_function
        if channels is not self._channels:
            self._rebuild(channels.names if channels is not None and ctf is not None else ())
            self._channels = channels
        if channels is None or ctf is None:
            self.note.setText(NO_CHANNELS)
            self.note.show()
            return
        if state.channels_drawn:
            self.note.hide()
        else:
            self.note.setText(TWO_D)
            self.note.show()
        for c in range(ctf.count):
            check, spin = self.show_box(c), self.weight_box(c)
            with signals_blocked(check, spin):
                check.setChecked(ctf.visible[c])
                spin.setValue(ctf.weights[c])
            rgb = channel_color(ctf.tfs[c])
            swatch = QPixmap(14, 14)
            swatch.fill(qcolor(rgb))
            button = self.color_button(c)
            button.setIcon(QIcon(swatch))
            button.setToolTip(f"{qcolor(rgb).name()}: click to draw the channel in another colour")
        with signals_blocked(self.table):
            self.table.setCurrentCell(state.selected_channel, NAME)

    def _rebuild(self, names: tuple[str, ...]) -> None:
        """One row per channel, for another volume."""
        self._names = names
        with signals_blocked(self.table):
            self.table.setRowCount(len(names))
        for c, name in enumerate(names):
            check = QCheckBox(self.table)
            check.setToolTip(f"Draw channel {name}")
            check.toggled.connect(lambda on, ch=c: self.set_visible(ch, on))
            button = QPushButton(self.table)
            button.setFlat(True)
            button.clicked.connect(lambda _checked=False, ch=c: self.pick_color(ch))
            spin = QDoubleSpinBox(self.table)
            spin.setRange(0.0, MAX_WEIGHT)
            spin.setSingleStep(0.1)
            spin.setDecimals(2)
            spin.setKeyboardTracking(False)  # apply on Enter or a step, not per keystroke
            spin.setToolTip("The channel's weight: a scale of its density (0 adds nothing)")
            spin.valueChanged.connect(lambda value, ch=c: self.set_weight(ch, value))
            item = QTableWidgetItem(name)
            item.setToolTip(f"channel {c}: select to edit its transfer function")
            item.setFlags(Qt.ItemFlags(Qt.ItemFlag.ItemIsSelectable) | Qt.ItemFlag.ItemIsEnabled)
            self.table.setItem(c, NAME, item)
            for column, widget in ((SHOW, check), (COLOUR, button), (WEIGHT, spin)):
                self.table.setCellWidget(c, column, widget)

    # ------------------------------------------------------------------ edits
    def select(self, channel: int) -> None:
        """Have the 1D editor edit `channel`'s TF."""
        if 0 <= channel < self.count:
            self.state.select_channel(channel)

    def set_visible(self, channel: int, visible: bool) -> None:
        ctf = self.state.channel_transfer_function
        if ctf is not None and ctf.visible[channel] != bool(visible):
            ctf.set_visible(channel, visible)

    def set_weight(self, channel: int, weight: float) -> None:
        """The channel's weight (0..MAX_WEIGHT): its density's scale."""
        ctf = self.state.channel_transfer_function
        weight = min(max(float(weight), 0.0), MAX_WEIGHT)
        if ctf is not None and ctf.weights[channel] != weight:
            ctf.set_weight(channel, weight)

    def set_color(self, channel: int, rgb: tuple[float, float, float]) -> None:
        """Draw the channel in the one colour `rgb` (a new TF: undo puts the old one back)."""
        ctf = self.state.channel_transfer_function
        if ctf is not None:
            ctf.set_tf(channel, recoloured(ctf.tfs[channel], rgb))

    def choose_color(self, initial: QColor) -> QColor | None:
        """Ask for a colour starting from `initial`; None when the person cancels."""
        color = QColorDialog.getColor(initial, self, "Channel colour")
        return color if color.isValid() else None

    def pick_color(self, channel: int) -> None:
        ctf = self.state.channel_transfer_function
        if ctf is None:
            return
        color = self.choose_color(qcolor(channel_color(ctf.tfs[channel])))
        if color is not None:
            self.set_color(channel, (color.redF(), color.greenF(), color.blueF()))
