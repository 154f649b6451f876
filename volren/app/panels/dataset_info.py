"""The dataset panel: which of the file's fields is shown (a chooser, as ParaView's colour-by
box), read-only facts about the loaded volume, and what loading changed.

The notes a load leaves on the volume (cells dropped or split into tetrahedra, tetrahedra
repaired, values converted, NaNs found; see `volren.io.dataset`) are listed one per line: they
are why a rendering may not look like the file in another program, so they stay in view instead
of vanishing with the status-bar message.

Nothing a file holds widens the dock: facts wrap (a label above its value when the dock is
narrow), names too long for it are elided in the middle (whole in their tooltips), and the
array chooser is as wide as the dock.
"""

from __future__ import annotations

from collections.abc import Sequence

from PyQt5.QtCore import QSize, Qt, pyqtSignal
from PyQt5.QtGui import QPainter, QPaintEvent
from PyQt5.QtWidgets import QComboBox, QFormLayout, QLabel, QListWidget, QVBoxLayout, QWidget

from volren.app.core.state import Change, ViewState
from volren.app.panels.base import StatePanel
from volren.model.crop import cropped_dimensions
from volren.model.volume import UniformVolume, Volume

NO_VOLUME = "No volume"
#: The facts that are names (no spaces to wrap at): elided in the middle instead.
NAME_FACTS = frozenset({"Name", "Array"})
#: The fewest characters an elided name or the array chooser shows.
MIN_NAME_CHARS = 12


class ElidedLabel(QLabel):
    """One line showing as much of its text as fits, the middle elided (a file name keeps its
    start and its suffix); the whole text is its tooltip and what `text()` gives."""

    def __init__(self, text: str, parent: QWidget | None = None) -> None:
        super().__init__(text, parent)
        self.setToolTip(text)

    def minimumSizeHint(self) -> QSize:
        hint = super().minimumSizeHint()
        return QSize(min(hint.width(), self.fontMetrics().averageCharWidth() * MIN_NAME_CHARS), hint.height())

    def paintEvent(self, event: QPaintEvent) -> None:
        rect = self.contentsRect()
        shown = self.fontMetrics().elidedText(self.text(), Qt.ElideMiddle, rect.width())
        painter = QPainter(self)
        painter.drawText(rect, int(self.alignment()), shown)
        painter.end()  # now, not whenever the wrapper is collected (Qt warns of a painter left active)


def _fact_label(label: str, text: str, parent: QWidget) -> QLabel:
    """A fact's value: a name elided, anything else wrapped at its spaces and selectable."""
    if label in NAME_FACTS:
        return ElidedLabel(text, parent)
    value = QLabel(text, parent)
    value.setWordWrap(True)
    value.setTextInteractionFlags(Qt.TextSelectableByMouse)
    return value


def _num(value: float) -> str:
    return f"{float(value):.6g}"


def _triple(values: Sequence[float]) -> str:
    return ", ".join(_num(v) for v in values)


def _bounds(bounds: Sequence[float]) -> str:
    return " × ".join(f"[{_num(bounds[2 * a])}, {_num(bounds[2 * a + 1])}]" for a in range(3))


def _size(volume: Volume) -> str:
    if isinstance(volume, UniformVolume):
        return " × ".join(str(n) for n in volume.dimensions)
    return f"{len(volume.tets):,} tetrahedra"


def array_label(choice: str) -> str:
    """How a field is named to people: "velocity (magnitude)", "velocity (x)", or the array's name."""
    name, sep, component = choice.rpartition(":")
    return f"{name} ({component})" if sep and name else choice


def volume_facts(volume: Volume, crop: Sequence[float] | None = None) -> list[tuple[str, str]]:
    """(label, text) rows describing `volume`, cropped to the box `crop` if given: a grid's cut
    counted in samples (`cropped_dimensions`, no copy of them), a mesh's as its box (a mesh's cut
    is not counted in cells while a face is dragged: that is the renderer's work, not the window's)."""
    rows = [("Name", volume.name)]
    if volume.scalars:
        rows.append(("Array", array_label(volume.scalars)))
    if isinstance(volume, UniformVolume):
        nx, ny, nz = volume.dimensions
        rows += [
            ("Kind", "uniform grid"),
            ("Dimensions", _size(volume)),
            ("Points", f"{nx * ny * nz:,}"),
            ("Cells", f"{(nx - 1) * (ny - 1) * (nz - 1):,}"),
            ("Spacing", _triple(volume.spacing)),
            ("Origin", _triple(volume.origin)),
        ]
    else:
        rows += [
            ("Kind", "tetrahedral mesh"),
            ("Points", f"{len(volume.points):,}"),
            ("Cells", f"{len(volume.tets):,} tetrahedra"),
            ("Mean edge length", _num(volume.mean_edge_length)),
        ]
    low, high = volume.value_range
    rows += [
        ("Bounds", _bounds(volume.bounds)),
        ("Data type", str(volume.values.dtype)),
        ("Value range", f"{_num(low)} to {_num(high)}"),
        ("Non-finite values", f"{volume.nonfinite_count:,}"),
    ]
    if crop is not None and isinstance(volume, UniformVolume):
        rows.append(("Cropped to", " × ".join(str(n) for n in cropped_dimensions(volume, crop))))
    elif crop is not None:
        rows.append(("Cropped to", _bounds(crop)))
    return rows


class DatasetInfoPanel(StatePanel):
    """The field chooser, a read-only form of `volume_facts` and the list of the volume's notes.
    Choosing a field emits `arrayChosen(choice)`: the window reloads the file with it."""

    watches = frozenset({"volume", "crop"})
    arrayChosen = pyqtSignal(str)

    def __init__(self, state: ViewState, parent: QWidget | None = None) -> None:
        super().__init__(state, parent)
        self.array_box = QComboBox(self)
        self.array_box.setSizeAdjustPolicy(QComboBox.AdjustToMinimumContentsLengthWithIcon)  # long names
        self.array_box.setMinimumContentsLength(MIN_NAME_CHARS)
        self.array_box.activated.connect(self._array_activated)
        array_row = QFormLayout()
        array_row.setRowWrapPolicy(QFormLayout.WrapLongRows)
        array_row.addRow("Show array", self.array_box)
        self.empty = QLabel(NO_VOLUME, self)
        self.form = QFormLayout()
        self.form.setRowWrapPolicy(QFormLayout.WrapLongRows)
        self.notes_label = QLabel("Notes", self)
        self.notes_list = QListWidget(self)
        self.notes_list.setToolTip("What loading changed or ignored (also reported as warnings)")
        self.notes_list.setWordWrap(True)
        layout = QVBoxLayout(self)
        layout.addLayout(array_row)
        layout.addWidget(self.empty)
        layout.addLayout(self.form)
        layout.addWidget(self.notes_label)
        layout.addWidget(self.notes_list)
        self._values: dict[str, QLabel] = {}
        self.refresh()

    def facts(self) -> dict[str, str]:
        """The facts as shown, label to text."""
        return {label: widget.text() for label, widget in self._values.items()}

    def notes(self) -> list[str]:
        """The notes as shown."""
        return [self.notes_list.item(i).text() for i in range(self.notes_list.count())]

    def _array_activated(self, index: int) -> None:
        choice = self.array_box.itemData(index)
        volume = self.state.volume
        if volume is not None and choice and choice != volume.scalars:
            self.arrayChosen.emit(choice)

    def _refresh_arrays(self, volume: Volume | None) -> None:
        """The file's fields, the shown one selected; disabled (saying why) with nothing to choose."""
        box = self.array_box
        box.blockSignals(True)
        box.clear()
        choices = list(volume.arrays) if volume is not None else []
        if volume is not None and volume.scalars and volume.scalars not in choices:
            choices.insert(0, volume.scalars)
        for choice in choices:
            box.addItem(array_label(choice), choice)
            box.setItemData(box.count() - 1, array_label(choice), Qt.ToolTipRole)
        if volume is not None and volume.scalars in choices:
            box.setCurrentIndex(choices.index(volume.scalars))
        box.blockSignals(False)
        box.setEnabled(len(choices) > 1)
        if volume is None:
            why = "Open a volume first"
        elif len(choices) > 1:
            why = (
                "The scalar field to render: another array of the file, or a vector's magnitude or component"
            )
        elif volume.arrays:
            why = "The file holds this one scalar field"
        else:
            why = "This volume was not read from a file with named arrays"
        box.setToolTip(why)

    def _on_change(self, change: Change) -> None:
        if change.what == "crop":  # a crop face's drag: the facts' texts only, at every step
            self._refresh_facts()
        else:
            super()._on_change(change)

    def refresh(self) -> None:
        volume = self.state.volume
        self._refresh_arrays(volume)
        self.notes_list.clear()
        self.empty.setVisible(volume is None)
        self._refresh_facts()
        if volume is None:
            self.notes_label.hide()
            self.notes_list.hide()
            return
        self.notes_list.addItems(list(volume.notes))
        self.notes_label.setText(f"Notes ({len(volume.notes)})" if volume.notes else "Notes: none")
        self.notes_label.show()
        self.notes_list.setVisible(bool(volume.notes))

    def _refresh_facts(self) -> None:
        """The form's rows: their texts set in place where the labels stay (rebuilding the form's
        widgets took 8 ms of the GUI thread at each step of a crop face's drag on bonsai)."""
        volume = self.state.volume
        facts: list[tuple[str, str]] = []
        if volume is not None:
            crop = self.state.crop
            if crop is not None and not isinstance(volume, UniformVolume):
                crop = self.state.shown_bounds
            facts = volume_facts(volume, crop)
        if [label for label, _ in facts] == list(self._values):
            for label, text in facts:
                widget = self._values[label]
                if widget.text() != text:
                    widget.setText(text)
                    widget.setToolTip(text if isinstance(widget, ElidedLabel) else "")
            return
        while self.form.rowCount():
            self.form.removeRow(0)
        self._values = {}
        for label, text in facts:
            value = _fact_label(label, text, self)
            self.form.addRow(label, value)
            self._values[label] = value
