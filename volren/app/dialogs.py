"""Message boxes, in one place so tests (and headless runs) can replace them.

Every error the app shows is a one-line reason (VolrenError's contract), never a traceback.
"""

from __future__ import annotations

from PyQt5.QtWidgets import QMessageBox, QWidget


def show_error(parent: QWidget | None, title: str, message: str) -> None:
    """A modal error box; looked up at call time so `QMessageBox.critical` can be patched."""
    QMessageBox.critical(parent, title, message)
