"""File > Save Screenshot: the view rendered at a chosen size in the background (with a progress
dialog that can cancel it), or the viewport or the whole window grabbed as shown."""

from __future__ import annotations

import os
from collections.abc import Callable

from PyQt5.QtCore import QObject, pyqtSignal
from PyQt5.QtGui import QKeySequence
from PyQt5.QtWidgets import QAction, QMainWindow

from volren.app.core.loading import PathArg
from volren.app.core.state import ViewState
from volren.app.files import screenshot_dialog
from volren.app.files.screenshot import ScreenshotJob, Screenshotter, check_writable
from volren.app.rendering.render_service import RendererFactory
from volren.app.rendering.viewport import Viewport
from volren.app.window.job_progress import JobProgress
from volren.errors import VolrenError


class ScreenshotActions(QObject):
    """The Save Screenshot action, its dialog, `render` and `save`; `saved(path)` after each PNG."""

    saved = pyqtSignal(str)

    def __init__(
        self,
        window: QMainWindow,
        state: ViewState,
        viewport: Viewport,
        renderer_factory: RendererFactory,
        report_error: Callable[[str, str], None],
        folder: Callable[[], str] | None = None,
    ) -> None:
        """`folder()`: where the person works now (the first screenshot is proposed there)."""
        super().__init__(window)
        self._window = window
        self._state = state
        self._viewport = viewport
        self._report_error = report_error
        self._folder = folder
        self._path = "volren.png"  # the dialog offers the last one again
        self._progress: JobProgress | None = None
        self.screenshotter = Screenshotter(renderer_factory, self)
        self.screenshotter.busyChanged.connect(self._on_busy)
        self.screenshotter.progressed.connect(self._on_progress)
        self.screenshotter.saved.connect(self._on_saved)
        self.screenshotter.failed.connect(lambda message: report_error("Cannot save the screenshot", message))
        self.action = QAction(
            "Save Screens&hot…", window, shortcut=QKeySequence("Ctrl+Shift+S"), triggered=self._dialog
        )
        self.action.setToolTip("Render the view at a chosen resolution and save it as PNG")

    def save(self, path: PathArg, whole_window: bool = False) -> bool:
        """Write the viewport (or the whole window) as shown, as PNG; reports and returns False on
        failure. `render` renders at a chosen size instead."""
        pixmap = (self._window if whole_window else self._viewport).grab()
        if not pixmap.save(str(path), "PNG"):
            self._report_error("Cannot save the screenshot", f"{path}: cannot write a PNG file there")
            return False
        self._on_saved(str(path))
        return True

    def render(self, path: PathArg, width: int, height: int) -> bool:
        """Render a full-quality `width` x `height` frame of the view with the current renderer in
        the background and write it as PNG (`saved` or a reported error follow); False when it
        cannot even start (nothing shown, a folder that cannot be written)."""
        try:
            check_writable(path)
            job = ScreenshotJob.of_view(self._state, path, width, height)
        except VolrenError as exc:
            self._report_error("Cannot save the screenshot", str(exc))
            return False
        self._close_progress()
        text = f"Rendering {job.width} x {job.height} with {job.renderer}…"
        self._progress = JobProgress(self._window, "Save screenshot", text, self.screenshotter.cancel)
        self.screenshotter.start(job)
        return True

    def _dialog(self) -> None:
        path = self._path if self._folder is None or os.path.isabs(self._path) else os.path.join(self._folder(), self._path)
        choice = screenshot_dialog.ask_screenshot(self._window, path, self._viewport.pixel_size())
        if choice is None:
            return
        self._path = choice.path
        if choice.whole_window:
            self.save(choice.path, whole_window=True)
        else:
            self.render(choice.path, choice.width, choice.height)

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
        """Close the progress dialog and wait for a screenshot still rendering."""
        self._close_progress()
        self.screenshotter.shutdown()
