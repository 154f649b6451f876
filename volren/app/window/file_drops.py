"""Drag and drop: a local file dropped on the window is opened like File > Open.

An event filter rather than overridden drag handlers, so the window class stays free of it: it
accepts a drag that carries a local file (so the cursor says it can be dropped) and announces the
dropped file's path; anything else is ignored.
"""

from __future__ import annotations

from PyQt5.QtCore import QEvent, QObject, pyqtSignal
from PyQt5.QtGui import QDragEnterEvent, QDragMoveEvent, QDropEvent


def dropped_path(event: QDragEnterEvent | QDragMoveEvent | QDropEvent) -> str | None:
    """The first local file the drag carries, or None."""
    mime = event.mimeData()
    if mime is None or not mime.hasUrls():
        return None
    for url in mime.urls():
        if url.isLocalFile():
            return url.toLocalFile()
    return None


class FileDrops(QObject):
    """Install on a widget that accepts drops; `dropped(path)` for each local file dropped."""

    dropped = pyqtSignal(str)

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:
        if event.type() not in (QEvent.DragEnter, QEvent.DragMove, QEvent.Drop):
            return False
        assert isinstance(event, QDropEvent)  # drag-enter and drag-move events are drop events too
        path = dropped_path(event)
        if path is None:
            event.ignore()
            return True
        event.acceptProposedAction()
        if event.type() == QEvent.Drop:
            self.dropped.emit(path)
        return True
