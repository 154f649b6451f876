"""File > Export Movie: an orbit of the view rendered into MP4 or GIF off the GUI thread.

Like a screenshot, the movie gets its own renderer in a pool thread, from a snapshot of the view
(camera, volume as cropped, TF, settings, background), so the person can go on working; Cancel
stops it at the next frame (or sooner, through a renderer's progress) and leaves no file. Its
frames are `volren.movie.record_movie`'s: what `volren movie` makes of the same view.
"""

from __future__ import annotations

from dataclasses import dataclass

from PyQt5.QtCore import QObject

from volren.app.core.loading import PathArg
from volren.app.core.state import ViewState
from volren.app.files.background_job import BackgroundJobs
from volren.app.files.screenshot import ScreenshotJob, job_drawing
from volren.app.rendering.render_service import RendererFactory, _registry_factory
from volren.io.movie_io import check_movie_path
from volren.model.animation import Animation
from volren.renderers.base import ProgressCallback


@dataclass(frozen=True, eq=False)
class MovieJob:
    """One movie: the view's snapshot (with the movie's path and frame size) and its timeline."""

    view: ScreenshotJob
    animation: Animation
    lossless: bool = False

    @classmethod
    def of_view(cls, state: ViewState, path: PathArg, width: int, height: int, animation: Animation,
                lossless: bool = False) -> MovieJob:  # fmt: skip
        """The job for what `state` shows now; VolrenError if nothing is, or the file cannot be a movie."""
        check_movie_path(path)
        return cls(ScreenshotJob.of_view(state, path, width, height), animation, lossless)


def record_job(job: MovieJob, factory: RendererFactory = _registry_factory,
               progress: ProgressCallback | None = None) -> str:  # fmt: skip
    """Render and write `job`'s movie; returns its path."""
    from volren.movie import record_movie

    view = job.view
    with job_drawing(view, factory) as drawing:
        record_movie(drawing.renderer, job.animation, view.camera, view.tf, view.bounds, (view.width, view.height),
                     view.path, view.background, job.lossless, progress, view.renderer)  # fmt: skip
    return str(view.path)


class MovieExporter(BackgroundJobs):
    """Records `MovieJob`s one at a time in the background (see `BackgroundJobs`)."""

    def __init__(self, factory: RendererFactory = _registry_factory, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._factory = factory

    def start(self, job: MovieJob) -> int:
        return self.start_work(lambda progress: record_job(job, self._factory, progress))
