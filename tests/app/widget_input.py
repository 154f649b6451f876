"""Showing a widget and sending it mouse input in tests.

Qt's test mouseMove does not deliver moves to a widget in the offscreen platform, so moves and
drags send the QMouseEvents themselves; presses and releases go through qtbot.
"""

from __future__ import annotations

from typing import TypeVar

from PyQt5.QtCore import QEvent, QPoint, QPointF, Qt
from PyQt5.QtGui import QMouseEvent
from PyQt5.QtWidgets import QApplication, QWidget

W = TypeVar("W", bound=QWidget)


def shown(qtbot, widget: W, size: tuple[int, int]) -> W:
    """`widget` at `size`, owned by qtbot (closed after the test) and exposed on screen."""
    widget.resize(*size)
    qtbot.addWidget(widget)
    widget.show()
    qtbot.waitExposed(widget)
    return widget


def move(widget: QWidget, pos: QPoint | QPointF) -> None:
    """A mouse move with the left button held (a drag's move)."""
    event = QMouseEvent(QEvent.MouseMove, QPointF(pos), Qt.NoButton, Qt.LeftButton, Qt.NoModifier)
    QApplication.sendEvent(widget, event)


def hover(widget: QWidget, pos: QPoint | QPointF) -> None:
    """A mouse move with no button held."""
    event = QMouseEvent(QEvent.MouseMove, QPointF(pos), Qt.NoButton, Qt.NoButton, Qt.NoModifier)
    QApplication.sendEvent(widget, event)


def drag(qtbot, widget: QWidget, start: QPoint, end: QPoint, steps: int = 4) -> None:
    """Press at `start`, `steps` moves on the straight line to `end`, release there."""
    qtbot.mousePress(widget, Qt.LeftButton, pos=start)
    for k in range(1, steps + 1):
        move(widget, start + (end - start) * (k / steps))
    qtbot.mouseRelease(widget, Qt.LeftButton, pos=end)
