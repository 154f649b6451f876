"""The progress dialog of a background job (a screenshot, a movie): it appears once the job has
run for a moment, counts the seconds until the job reports a fraction, and Cancel stops the job.
`FileJobActions` is what the File menu's job actions share around it.

Why the clock: a QProgressDialog shows itself only from setValue, and a renderer that reports no
progress never calls it: a 20 s screenshot gave no feedback at all.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable

from PyQt5.QtCore import QObject, QTimer, pyqtSignal
from PyQt5.QtWidgets import QMainWindow, QProgressDialog, QWidget

from volren.app.files.background_job import BackgroundJobs

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


class FileJobActions(QObject):
    """What the File menu's background jobs (Save Screenshot, Export Movie) share: the job runner's
    signals wired to a `JobProgress` dialog and the status bar, the path the dialog proposes (the
    last one, in the folder the person works in), and `shutdown`. `saved(path)` after each file."""

    saved = pyqtSignal(str)

    def __init__(self, window: QMainWindow, jobs: BackgroundJobs, error_title: str, first_name: str,
                 report_error: Callable[[str, str], None], folder: Callable[[], str] | None = None) -> None:  # fmt: skip
        """`folder()`: where the person works now (the first file is proposed there)."""
        super().__init__(window)
        self._window = window
        self._jobs = jobs
        self._error_title = error_title
        self._report_error = report_error
        self._folder = folder
        self._path = first_name  # the dialog offers the last one again
        self._progress: JobProgress | None = None
        jobs.setParent(self)
        jobs.busyChanged.connect(self._on_busy)
        jobs.progressed.connect(self._on_progress)
        jobs.saved.connect(self._on_saved)
        jobs.failed.connect(lambda message: report_error(error_title, message))

    def _proposed_path(self) -> str:
        if self._folder is None or os.path.isabs(self._path):
            return self._path
        return os.path.join(self._folder(), self._path)

    def _show_progress(self, title: str, text: str) -> None:
        """A new progress dialog for the job about to start (Cancel stops it)."""
        self._close_progress()
        self._progress = JobProgress(self._window, title, text, self._jobs.cancel)

    def _on_progress(self, fraction: float) -> None:
        if self._progress is not None:
            self._progress.report(fraction)

    def _on_busy(self, busy: bool) -> None:
        if not busy:
            self._close_progress()

    def _close_progress(self) -> None:
        progress, self._progress = self._progress, None
        if progress is not None:
            progress.close()

    def _on_saved(self, path: str) -> None:
        self._window.statusBar().showMessage(f"Saved {path}", 5000)
        self.saved.emit(path)

    def shutdown(self) -> None:
        """Close the progress dialog and stop the job still running (its file is not written)."""
        self._close_progress()
        self._jobs.shutdown()
