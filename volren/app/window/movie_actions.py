"""File > Export Movie: an orbit of the view rendered into MP4 or GIF in the background, with a
progress dialog that counts frames and can cancel (`volren.app.files.movie_export`).

The dialog opens with the last movie's frame size, frames, speed, orbit and lossless (kept in the
app's settings, so across sessions too); the first time, with the viewport's size and defaults.
"""

from __future__ import annotations

from collections.abc import Callable

from PyQt5.QtCore import QSettings
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
#: Where the app's settings keep the last movie's dialog fields (`MovieFields.to_json`).
FIELDS_KEY = "dialogs/movie"


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
        settings: QSettings | None = None,
    ) -> None:
        """`folder()`: where the person works now (the first movie is proposed there);
        `settings`: where the last movie's dialog fields are kept (None: for this session only)."""
        self.exporter = MovieExporter(renderer_factory)
        super().__init__(window, self.exporter, ERROR_TITLE, "volren.mp4", report_error, folder)
        self._state = state
        self._viewport = viewport
        self._settings = settings
        self._fields = (
            movie_dialog.MovieFields.from_json(settings.value(FIELDS_KEY)) if settings is not None else None
        )
        self._frames = 0
        self.action = QAction("Export &Movie…", window, triggered=self._dialog)
        self.action.setToolTip("Render an orbit of the view into an MP4 or GIF movie")

    def export(
        self, path: PathArg, width: int, height: int, animation: Animation, lossless: bool = False
    ) -> bool:
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

    def dialog_fields(self) -> movie_dialog.MovieFields:
        """What the dialog opens with: the last movie's fields, else the viewport's size and defaults."""
        return self._fields or movie_dialog.MovieFields(*self._viewport.pixel_size())

    def _remember(self, fields: movie_dialog.MovieFields) -> None:
        self._fields = fields
        if self._settings is not None:
            self._settings.setValue(FIELDS_KEY, fields.to_json())

    def _dialog(self) -> None:
        choice = movie_dialog.ask_movie(self._window, self._proposed_path(), self.dialog_fields())
        if choice is None:
            return
        self._path = choice.path
        self._remember(choice.fields())
        self.export(choice.path, choice.width, choice.height, choice.animation, choice.lossless)

    def _on_progress(self, fraction: float) -> None:
        if self._progress is not None:
            frame = min(int(fraction * self._frames) + 1, self._frames)
            self._progress.report(fraction, f"Rendering frame {frame} of {self._frames}…")
