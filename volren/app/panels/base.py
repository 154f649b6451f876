"""`StatePanel`: the base of the settings panels, a widget that mirrors part of a `ViewState`.

A panel never keeps its own copy of what it edits. It writes through the state's setters and
redraws its widgets from the state whenever the parts it `watches` change, wherever the change
came from (this panel, a loaded scene, undo). Redrawing happens with the widgets' signals
blocked, so showing a value never reads as an edit and never loops back into the state.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import ClassVar

from PyQt5.QtCore import QObject
from PyQt5.QtGui import QColor
from PyQt5.QtWidgets import QAbstractItemView, QHeaderView, QTableWidget, QWidget

from volren.app.core.state import Change, ViewState, What
from volren.app.qt_subscription import subscribe_while_alive


@contextmanager
def signals_blocked(*objects: QObject) -> Iterator[None]:
    """Set widget values without their change signals firing (the value came from the state)."""
    previous = [o.blockSignals(True) for o in objects]
    try:
        yield
    finally:
        for o, was in zip(objects, previous, strict=True):
            o.blockSignals(was)


class StatePanel(QWidget):
    """A widget that shows part of `state` and follows its changes; subclasses fill in `refresh`."""

    #: The parts of the state this panel shows: a change of any of them calls `refresh`.
    watches: ClassVar[frozenset[What]] = frozenset()

    def __init__(self, state: ViewState, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.state = state
        self._unsubscribe = subscribe_while_alive(state, self, "_on_change")

    def _on_change(self, change: Change) -> None:
        if change.what in self.watches:
            self.refresh()

    def refresh(self) -> None:
        """Show what the state holds now, without emitting edits."""
        raise NotImplementedError

    def detach(self) -> None:
        """Stop following the state (the window is closing, or the panel is replaced)."""
        self._unsubscribe()


def unsupported(state: ViewState, feature: str) -> str:
    """The tooltip of a control the current renderer cannot honour, e.g. "The vtk renderer has no
    pre-integration for tet volumes"."""
    volume = state.volume
    where = f" for {volume.kind} volumes" if volume is not None else ""
    return f"The {state.renderer} renderer has no {feature}{where}"


def qcolor(rgb: tuple[float, float, float]) -> QColor:
    """A colour (r, g, b) in 0..1, clamped, as Qt takes it."""
    return QColor.fromRgbF(*(min(max(float(c), 0.0), 1.0) for c in rgb))


def row_table(parent: QWidget, columns: tuple[str, ...], stretch: int) -> QTableWidget:
    """A list of items as rows (the Labels and Channels panels): one row selected at a time, cells
    edited by their own widgets only, columns as wide as their contents but `stretch`, which takes
    the rest."""
    table = QTableWidget(0, len(columns), parent)
    table.setHorizontalHeaderLabels(columns)
    rows = table.verticalHeader()
    assert rows is not None
    rows.hide()
    table.setSelectionBehavior(QAbstractItemView.SelectRows)
    table.setSelectionMode(QAbstractItemView.SingleSelection)
    table.setEditTriggers(QAbstractItemView.NoEditTriggers)
    header = table.horizontalHeader()
    assert header is not None
    for column in range(len(columns)):
        header.setSectionResizeMode(column, QHeaderView.ResizeToContents)
    header.setSectionResizeMode(stretch, QHeaderView.Stretch)
    return table
