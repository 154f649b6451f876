"""File > Export Movie: an orbit of the view rendered into MP4 or GIF in the background, with a
progress dialog that counts frames and can cancel (`volren.app.files.movie_export`)."""

from __future__ import annotations

import os
from collections.abc import Callable

from PyQt5.QtCore import QObject, pyqtSignal
from PyQt5.QtWidgets import QAction, QMainWindow

from volren.app.core.loading import PathArg
from volren.app.core.state import ViewState
from volren.app.files import movie_dialog
from volren.app.files.movie_export import MovieExporter, MovieJob
from volren.app.rendering.render_service import RendererFactory
from volren.app.rendering.viewport import Viewport
from volren.app.window.job_progress import JobProgress
from volren.errors import VolrenError
from volren.model.animation import Animation

ERROR_TITLE = "Cannot export the movie"


class MovieActions(QObject):
    """The Export Movie action, its dialog and `export`; `saved(path)` after each movie."""

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
        """`folder()`: where the person works now (the first movie is proposed there)."""
        super().__init__(window)
        self._window = window
        self._state = state
        self._viewport = viewport
        self._report_error = report_error
        self._folder = folder
        self._path = "volren.mp4"  # the dialog offers the last one again
        self._progress: JobProgress | None = None
        self._frames = 0
        self.exporter = MovieExporter(renderer_factory, self)
        self.exporter.busyChanged.connect(self._on_busy)
        self.exporter.progressed.connect(self._on_progress)
        self.exporter.saved.connect(self._on_saved)
        self.exporter.failed.connect(lambda message: report_error(ERROR_TITLE, message))
        self.action = QAction("Export &Movie…", window, triggered=self._dialog)
        self.action.setToolTip("Render an orbit of the view into an MP4 or GIF movie")

    def export(self, path: PathArg, width: int, height: int, animation: Animation, lossless: bool = False) -> bool:
        """Record `animation` from the current view at `width` x `height` with the current renderer
        in the background (`saved` or a reported error follow); False when it cannot even start."""
        try:
            job = MovieJob.of_view(self._state, path, width, height, animation, lossless)
        except VolrenError as exc:
            self._report_error(ERROR_TITLE, str(exc))
            return False
        self._close_progress()
        self._frames = animation.frames
        text = f"Rendering {animation.frames} frames of {width} x {height} with {job.view.renderer}…"
        self._progress = JobProgress(self._window, "Export movie", text, self.exporter.cancel)
        self.exporter.start(job)
        return True

    def _dialog(self) -> None:
        path = self._path if self._folder is None or os.path.isabs(self._path) else os.path.join(self._folder(), self._path)
        choice = movie_dialog.ask_movie(self._window, path, self._viewport.pixel_size())
        if choice is None:
            return
        self._path = choice.path
        self.export(choice.path, choice.width, choice.height, choice.animation, choice.lossless)

    def _on_progress(self, fraction: float) -> None:
        if self._progress is not None:
            frame = min(int(fraction * self._frames) + 1, self._frames)
            self._progress.report(fraction, f"Rendering frame {frame} of {self._frames}…")

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
        """Close the progress dialog and stop a movie still recording (its file is not written)."""
        self._close_progress()
        self.exporter.shutdown()
