"""The Labels panel: one row per label of a segmentation (as napari's and 3D Slicer's segment lists).

Each row shows a label's name and edits its `LabelStyle` (Real-Time Volume Graphics, chapter 16: a
transfer function per object): shown or hidden, its colour (in place of the 1D TF's colours), and
its opacity scale over the 1D TF's opacity. "Solo" shows one label alone; turning it off brings
back the visibility the labels had before. Edits go through `LabelTransferFunction.set_style(s)`,
so the frame follows like any TF edit. Selecting a row has the 1D editor edit that label's own TF
(`ViewState.edit_label`: an unstyled label gets its own on the first edit, a copy of the base TF);
"Edit base TF" goes back to the TF every label without its own draws with. A Ctrl+click on the
view selects the label seen there (`select_label`). The colour dialog is opened through `choose_color` alone, so
tests replace one method instead of a modal dialog.
"""

from __future__ import annotations

from dataclasses import replace

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
from volren.model.labels import LabelStyle

#: The largest opacity scale offered: four times the 1D TF's opacity makes a faint label solid.
MAX_OPACITY_SCALE = 4.0
COLUMNS = ("Show", "Colour", "Name", "Opacity", "Solo")
SHOW, COLOUR, NAME, OPACITY, SOLO = range(len(COLUMNS))
NO_LABELS = "No labels: File > Open Labels… draws a segmentation of the volume"
TWO_D = "Labels are not drawn with a 2D transfer function: switch the editor to 1D to draw them"


class LabelsPanel(StatePanel):
    """The labels of the volume shown, a row each: Show, Colour, Name, Opacity, Solo."""

    watches = frozenset({"volume", "tf"})

    def __init__(self, state: ViewState, parent: QWidget | None = None) -> None:
        super().__init__(state, parent)
        self.note = QLabel(self)
        self.note.setWordWrap(True)
        self.table = row_table(self, COLUMNS, NAME)
        self.table.currentCellChanged.connect(lambda row, *_: self._row_selected(row))
        self.editing = QLabel(self)
        self.editing.setWordWrap(True)
        self.base_button = QPushButton("Edit base TF", self)
        self.base_button.setToolTip("Have the 1D editor edit the TF that labels without their own draw with")
        self.base_button.clicked.connect(self.edit_base)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(2, 2, 2, 2)
        layout.addWidget(self.note)
        layout.addWidget(self.table)
        layout.addWidget(self.editing)
        layout.addWidget(self.base_button)
        self._labels: tuple[int, ...] = ()  # the label of each row
        self._before_solo: dict[int, bool] | None = None  # visibility before a label was soloed
        self._solo: int | None = None
        self.refresh()

    # ------------------------------------------------------------------ reading
    @property
    def labels(self) -> tuple[int, ...]:
        """The labels listed, a row each, ascending."""
        return self._labels

    def row_of(self, label: int) -> int:
        return self._labels.index(label)

    def selected_label(self) -> int | None:
        row = self.table.currentRow()
        return self._labels[row] if 0 <= row < len(self._labels) else None

    def show_box(self, label: int) -> QCheckBox:
        widget = self.table.cellWidget(self.row_of(label), SHOW)
        assert isinstance(widget, QCheckBox)
        return widget

    def color_button(self, label: int) -> QPushButton:
        widget = self.table.cellWidget(self.row_of(label), COLOUR)
        assert isinstance(widget, QPushButton)
        return widget

    def opacity_box(self, label: int) -> QDoubleSpinBox:
        widget = self.table.cellWidget(self.row_of(label), OPACITY)
        assert isinstance(widget, QDoubleSpinBox)
        return widget

    def solo_box(self, label: int) -> QCheckBox:
        widget = self.table.cellWidget(self.row_of(label), SOLO)
        assert isinstance(widget, QCheckBox)
        return widget

    # ------------------------------------------------------------------ following the state
    def refresh(self) -> None:
        state = self.state
        labels = state.labels
        label_tf = state.label_transfer_function
        present = labels.present if labels is not None else ()
        if present != self._labels:
            self._rebuild(present)
        edited = state.edited_label
        with signals_blocked(self.table):
            if edited is None:
                self.table.setCurrentCell(-1, -1)
            else:
                self.table.setCurrentCell(self.row_of(edited), NAME)
        self.base_button.setEnabled(edited is not None)
        if labels is None or label_tf is None:
            self.note.setText(NO_LABELS)
            self.note.show()
            self.editing.hide()
            return
        self.editing.show()
        if edited is None:
            self.editing.setText("The 1D editor edits the base TF (select a label to edit its own)")
        elif label_tf.style(edited).tf is None:
            self.editing.setText(
                f"The 1D editor edits {labels.label_name(edited)}: its own TF from the first edit"
            )
        else:
            self.editing.setText(f"The 1D editor edits {labels.label_name(edited)}'s own TF")
        if state.labels_drawn:
            self.note.hide()
        else:
            self.note.setText(TWO_D)
            self.note.show()
        for row, label in enumerate(self._labels):
            style = label_tf.style(label)
            name = self.table.item(row, NAME)
            assert name is not None
            name.setText(labels.label_name(label))
            check, spin, solo = self.show_box(label), self.opacity_box(label), self.solo_box(label)
            with signals_blocked(check, spin, solo):
                check.setChecked(style.visible)
                spin.setValue(style.opacity)
                solo.setChecked(self._solo == label)
            button = self.color_button(label)
            if style.color is None:
                button.setIcon(QIcon())
                button.setText("TF")
                button.setToolTip("Drawn in the transfer function's colours; click to give it one colour")
            else:
                swatch = QPixmap(14, 14)
                swatch.fill(qcolor(style.color))
                button.setIcon(QIcon(swatch))
                button.setText("")
                button.setToolTip(f"{qcolor(style.color).name()}: click to change the label's colour")

    def _rebuild(self, present: tuple[int, ...]) -> None:
        """One row per label, for another label map (solo forgotten: it belonged to the old one)."""
        self._labels = present
        self._solo, self._before_solo = None, None
        with signals_blocked(self.table):
            self.table.setRowCount(len(present))
        for row, label in enumerate(present):
            check = QCheckBox(self.table)
            check.setToolTip(f"Draw label {label}")
            check.toggled.connect(lambda on, lab=label: self.set_visible(lab, on))
            button = QPushButton(self.table)
            button.setFlat(True)
            button.clicked.connect(lambda _checked=False, lab=label: self.pick_color(lab))
            spin = QDoubleSpinBox(self.table)
            spin.setRange(0.0, MAX_OPACITY_SCALE)
            spin.setSingleStep(0.1)
            spin.setDecimals(2)
            spin.setKeyboardTracking(False)  # apply on Enter or a step, not per keystroke
            spin.setToolTip("The label's opacity, as a multiple of the transfer function's")
            spin.valueChanged.connect(lambda value, lab=label: self.set_opacity(lab, value))
            solo = QCheckBox(self.table)
            solo.setToolTip(f"Draw label {label} alone; untick to bring the others back")
            solo.toggled.connect(lambda on, lab=label: self.set_solo(lab, on))
            name = QTableWidgetItem(f"label {label}")
            name.setToolTip(f"label value {label}")
            name.setFlags(Qt.ItemFlags(Qt.ItemFlag.ItemIsSelectable) | Qt.ItemFlag.ItemIsEnabled)
            self.table.setItem(row, NAME, name)
            for column, widget in ((SHOW, check), (COLOUR, button), (OPACITY, spin), (SOLO, solo)):
                self.table.setCellWidget(row, column, widget)

    # ------------------------------------------------------------------ selection
    def _row_selected(self, row: int) -> None:
        self.state.edit_label(self._labels[row] if 0 <= row < len(self._labels) else None)

    def select_label(self, label: int) -> None:
        """Select `label`'s row: the 1D editor edits its TF (a pick in the view)."""
        if label in self._labels:
            self.table.setCurrentCell(self.row_of(label), NAME)

    def edit_base(self) -> None:
        """No label selected: the 1D editor edits the base TF."""
        self.state.edit_label(None)

    # ------------------------------------------------------------------ edits
    def _edit(self, label: int, **fields: object) -> None:
        label_tf = self.state.label_transfer_function
        if label_tf is None:
            return
        style = label_tf.style(label)
        changed = replace(style, **fields)  # type: ignore[arg-type]
        if changed != style:
            label_tf.set_style(label, changed)

    def set_visible(self, label: int, visible: bool) -> None:
        """Show or hide one label (ends a solo: the visibility is the person's again)."""
        self._solo, self._before_solo = None, None
        self._edit(label, visible=visible)

    def set_opacity(self, label: int, scale: float) -> None:
        """The label's opacity as `scale` times the 1D TF's (0..MAX_OPACITY_SCALE)."""
        self._edit(label, opacity=min(max(float(scale), 0.0), MAX_OPACITY_SCALE))

    def set_color(self, label: int, rgb: tuple[float, float, float] | None) -> None:
        """Draw the label in one colour (None: in the 1D TF's colours)."""
        self._edit(label, color=rgb)

    def set_solo(self, label: int, on: bool) -> None:
        """Show `label` alone (on), or bring back the visibility from before the solo (off)."""
        label_tf = self.state.label_transfer_function
        if label_tf is None:
            return
        if on:
            if self._before_solo is None:
                self._before_solo = {lab: label_tf.style(lab).visible for lab in self._labels}
            self._solo = label
            wanted = {lab: lab == label for lab in self._labels}
        else:
            if self._solo != label:
                return
            wanted = self._before_solo or {}
            self._solo, self._before_solo = None, None
        styles = {lab: replace(label_tf.style(lab), visible=v) for lab, v in wanted.items()
                  if label_tf.style(lab).visible != v}  # fmt: skip
        if styles:
            label_tf.set_styles(styles)
        else:
            self.refresh()  # the solo boxes

    def choose_color(self, initial: QColor) -> QColor | None:
        """Ask for a colour starting from `initial`; None when the person cancels."""
        color = QColorDialog.getColor(initial, self, "Label colour")
        return color if color.isValid() else None

    def pick_color(self, label: int) -> None:
        label_tf = self.state.label_transfer_function
        if label_tf is None:
            return
        style: LabelStyle = label_tf.style(label)
        color = self.choose_color(qcolor(style.color or (1.0, 1.0, 1.0)))
        if color is not None:
            self.set_color(label, (color.redF(), color.greenF(), color.blueF()))
