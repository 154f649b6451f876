"""File > Export Movie: an orbit of the view rendered into MP4 or GIF in the background, with a
progress dialog that counts frames and can cancel (`volren.app.files.movie_export`)."""

from __future__ import annotations

from collections.abc import Callable

from PyQt5.QtWidgets import QAction, QMainWindow

from volren.app.core.loading import PathArg
from volren.app.core.state import ViewState
from volren.app.files import movie_dialog
from volren.app.files.movie_export import MovieExporter, MovieJob
from volren.app.rendering.render_service import RendererFactory
from volren.app.rendering.viewport import Viewport
from volren.app.window.job_progress import FileJobActions
from volren.errors import VolrenError
from volren.model.animation import Animation

ERROR_TITLE = "Cannot export the movie"


class MovieActions(FileJobActions):
    """The Export Movie action, its dialog and `export`; `saved(path)` after each movie."""

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
        self.exporter = MovieExporter(renderer_factory)
        super().__init__(window, self.exporter, ERROR_TITLE, "volren.mp4", report_error, folder)
        self._state = state
        self._viewport = viewport
        self._frames = 0
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
        self._frames = animation.frames
        self._show_progress("Export movie", f"Rendering {animation.frames} frames of {width} x {height} with "
                            f"{job.view.renderer}…")  # fmt: skip
        self.exporter.start(job)
        return True

    def _dialog(self) -> None:
        choice = movie_dialog.ask_movie(self._window, self._proposed_path(), self._viewport.pixel_size())
        if choice is None:
            return
        self._path = choice.path
        self.export(choice.path, choice.width, choice.height, choice.animation, choice.lossless)

    def _on_progress(self, fraction: float) -> None:
        if self._progress is not None:
            frame = min(int(fraction * self._frames) + 1, self._frames)
            self._progress.report(fraction, f"Rendering frame {frame} of {self._frames}…")
