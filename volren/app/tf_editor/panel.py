"""The transfer-function dock: the 1D and the 2D editor in tabs, with undo and redo.

Both editors edit `state.transfer_function`; the tab that matches the TF in the state is brought
forward whenever the TF changes kind (a file opened, undo across a switch), so what is shown is
always what is rendered. The other tab offers to switch kinds (its "Use a ... transfer function"
button). Undo and redo come from one `TFHistory` shared by both editors.
"""

from __future__ import annotations

from collections.abc import Callable

from PyQt5.QtCore import pyqtSignal
from PyQt5.QtWidgets import QHBoxLayout, QTabWidget, QToolButton, QVBoxLayout, QWidget

from volren.app.core.state import Change, ViewState
from volren.app.tf_editor.history import TFHistory
from volren.app.tf_editor.one_d.editor import TransferFunction1DEditor
from volren.app.tf_editor.two_d.editor import TransferFunction2DEditor


class TransferFunctionPanel(QWidget):
    """Tabs "1D" and "2D" over one state; forwards the editors' errors."""

    errorOccurred = pyqtSignal(str, str)

    def __init__(self, state: ViewState, history: TFHistory, parent: QWidget | None = None,
                 two_d_reason: Callable[[str], str | None] = lambda _kind: None) -> None:  # fmt: skip
        """`two_d_reason(kind)`: why no renderer can draw a 2D TF on such volumes (None: one can)."""
        super().__init__(parent)
        self.state = state
        self.history = history
        self.editor_1d = TransferFunction1DEditor(state, self)
        self.editor_2d = TransferFunction2DEditor(state, self, two_d_reason)
        self.tabs = QTabWidget(self)
        self.tabs.addTab(self.editor_1d, "1D: value")
        self.tabs.addTab(self.editor_2d, "2D: value x gradient")
        self.tabs.setTabToolTip(0, "Colour and opacity by data value, over the value histogram")
        self.tabs.setTabToolTip(
            1, "Opacity widgets over the value x gradient-magnitude histogram (book ch. 10)"
        )

        self.undo_button = QToolButton(self)
        self.undo_button.setDefaultAction(history.stack.createUndoAction(self, "Undo"))
        self.redo_button = QToolButton(self)
        self.redo_button.setDefaultAction(history.stack.createRedoAction(self, "Redo"))
        buttons = QHBoxLayout()
        buttons.addWidget(self.undo_button)
        buttons.addWidget(self.redo_button)
        buttons.addStretch(1)

        layout = QVBoxLayout(self)
        layout.setContentsMargins(2, 2, 2, 2)
        layout.addLayout(buttons)
        layout.addWidget(self.tabs, 1)

        self.editor_1d.errorOccurred.connect(self.errorOccurred)
        self.editor_2d.errorOccurred.connect(self.errorOccurred)
        self._dims = 0
        self._unsubscribe = state.subscribe(self._on_change)
        self._follow_kind()

    def _on_change(self, change: Change) -> None:
        if change.what in ("tf", "volume"):
            self._follow_kind()

    def _follow_kind(self) -> None:
        tf = self.state.transfer_function
        dims = tf.dims if tf is not None else 1
        if dims != self._dims:
            self._dims = dims
            self.tabs.setCurrentIndex(dims - 1)

    def detach(self) -> None:
        self._unsubscribe()
