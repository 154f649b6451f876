"""The progress dialog of a background job (a screenshot, a movie): it appears once the job has
run for a moment, counts the seconds until the job reports a fraction, and Cancel stops the job.

Why the clock: a QProgressDialog shows itself only from setValue, and a renderer that reports no
progress never calls it: a 20 s screenshot gave no feedback at all (issue 23).
"""

from __future__ import annotations

import time
from collections.abc import Callable

from PyQt5.QtCore import QTimer
from PyQt5.QtWidgets import QProgressDialog, QWidget

#: A job still running after this (ms) shows its progress dialog; the clock ticks this often.
SHOW_PROGRESS_AFTER_MS = 400


class JobProgress:
    """One job's dialog: `report(fraction, text)` as it goes, `close()` when it ends."""

    def __init__(self, parent: QWidget, title: str, text: str, cancel: Callable[[], object]) -> None:
        self._text = text
        self._started = time.monotonic()
        self.dialog = QProgressDialog(text, "Cancel", 0, 0, parent)
        self.dialog.setWindowTitle(title)
        self.dialog.setMinimumDuration(SHOW_PROGRESS_AFTER_MS)
        self.dialog.setAutoClose(False)
        self.dialog.setAutoReset(False)
        self.dialog.canceled.connect(cancel)
        self._clock = QTimer(self.dialog)  # goes with the dialog
        self._clock.timeout.connect(self._tick)
        self._clock.start(SHOW_PROGRESS_AFTER_MS)

    def _tick(self) -> None:
        self.dialog.setLabelText(f"{self._text} {time.monotonic() - self._started:.0f} s")
        if not self.dialog.isVisible():
            self.dialog.show()

    def report(self, fraction: float, text: str | None = None) -> None:
        """A fraction done (0..1) turns the busy bar into a percentage; `text` replaces the label."""
        if text is not None:
            self._text = text
            self.dialog.setLabelText(text)
        self.dialog.setRange(0, 100)
        self.dialog.setValue(round(100 * min(max(fraction, 0.0), 1.0)))

    def close(self) -> None:
        self._clock.stop()
        self.dialog.canceled.disconnect()  # closing it would say "canceled"
        self.dialog.close()
        self.dialog.deleteLater()
