"""The undo keys in the docks' number fields: the field's own undo while it holds typing not yet
entered, the app's undo (the Edit menu's) otherwise.

A line edit or spin box claims Ctrl+Z, Ctrl+Shift+Z and Ctrl+Y for itself (it accepts the
ShortcutOverride) even with nothing of its own to undo, and it keeps the focus after Enter: so a
value typed and entered could not be taken back from the keyboard, though it is a TF edit like a
drag. While a value is being typed the keys still edit the typing, as in any text field; once it
is entered (or the field holds nothing typed), they undo and redo the app's edits.
"""

from __future__ import annotations

from collections.abc import Iterable

from PyQt5.QtCore import QEvent, QObject
from PyQt5.QtGui import QKeyEvent, QKeySequence
from PyQt5.QtWidgets import QAbstractSpinBox, QAction, QLineEdit, QWidget

#: Redo's keys on every platform besides its own standard ones (Qt's standard Redo is Ctrl+Y on
#: some platforms and Ctrl+Shift+Z on others; people coming from either expect theirs).
EXTRA_REDO_KEYS = (QKeySequence("Ctrl+Shift+Z"), QKeySequence("Ctrl+Y"))


def set_undo_shortcuts(undo: QAction, redo: QAction) -> None:
    """Every standard key of the platform for Undo and Redo, and both usual Redo keys."""
    undo.setShortcuts(QKeySequence.Undo)
    redo_keys = QKeySequence.keyBindings(QKeySequence.Redo)
    redo.setShortcuts(redo_keys + [key for key in EXTRA_REDO_KEYS if key not in redo_keys])


def _line_edit(field: QWidget) -> QLineEdit:
    return field.lineEdit() if isinstance(field, QAbstractSpinBox) else field  # type: ignore[return-value]


def _pressed(event: QKeyEvent) -> QKeySequence:
    return QKeySequence(int(event.modifiers()) | event.key())


class FieldUndoKeys(QObject):
    """Lets the undo keys through to `undo` and `redo` from the fields `watch` is given, unless
    the field has typing of its own to undo (or redo)."""

    def __init__(self, undo: QAction, redo: QAction, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._undo = undo
        self._redo = redo

    def watch(self, roots: Iterable[QWidget]) -> None:
        """Every spin box and line edit under `roots` (a spin box's own line edit through it)."""
        for root in roots:
            fields: list[QWidget] = list(root.findChildren(QAbstractSpinBox))
            fields += [
                e for e in root.findChildren(QLineEdit) if not isinstance(e.parentWidget(), QAbstractSpinBox)
            ]
            for field in fields:
                field.installEventFilter(self)
                edit = _line_edit(field)
                # entered: what was typed is the app's edit now, no longer the field's to undo
                field.editingFinished.connect(lambda edit=edit: edit.setModified(False))

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:
        if event.type() != QEvent.ShortcutOverride or not isinstance(watched, QWidget):
            return False
        keys = _pressed(event)  # type: ignore[arg-type]
        edit = _line_edit(watched)
        typing = edit.isModified()
        if keys in self._undo.shortcuts():
            own = typing and edit.isUndoAvailable()
        elif keys in self._redo.shortcuts():
            own = typing and edit.isRedoAvailable()
        else:
            return False
        if own:
            return False
        event.ignore()  # not the field's: the window's shortcut takes the key
        return True
