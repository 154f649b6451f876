"""File > Save Screenshot: a full-quality frame at a chosen resolution, rendered off the GUI thread.

Why not reuse the viewport's render thread: its mailbox keeps only the newest request, so the
next mouse move would replace (or interrupt) a large screenshot, and its frames go to the
viewport. A screenshot gets its own short-lived renderer instead, made, fed, used and released
in one pool thread (renderers own their GL context per thread and per instance), from a
snapshot of the view taken on the GUI thread: the person can go on editing while it renders.

The PNG holds what the viewport shows: the premultiplied frame over the view's background
(`volren.io.save_image`, the conversion every frame goes through).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from PyQt5.QtCore import QObject

from volren.app.core.loading import PathArg
from volren.app.core.preview_settings import still_settings
from volren.app.core.state import ViewState
from volren.app.files.background_job import BackgroundJobs
from volren.app.rendering.render_service import RendererFactory, _registry_factory
from volren.draw import Drawing, Preparation, VolumeInput, draw
from volren.errors import VolrenError
from volren.io.safe_write import check_output
from volren.model.camera import Camera
from volren.model.labels import LabelTransferFunction
from volren.model.scene import Scene
from volren.model.settings import RenderSettings
from volren.model.transfer_function_2d import TransferFunction
from volren.model.volume import Volume
from volren.renderers.base import ProgressCallback, Renderer


@dataclass(frozen=True, eq=False)
class ScreenshotJob:
    """One screenshot: where, how big, and a snapshot of the view (the TF is a private copy)."""

    path: Path
    width: int
    height: int
    renderer: str
    volume: Volume
    tf: TransferFunction | LabelTransferFunction
    settings: RenderSettings
    camera: Camera
    background: tuple[float, float, float]
    #: the bounds of what is drawn (the crop box's part of the volume's): a movie orbits around them
    bounds: tuple[float, ...]

    @classmethod
    def of_view(cls, state: ViewState, path: PathArg, width: int, height: int) -> ScreenshotJob:
        """The job for what `state` shows now (cropped volume included); VolrenError if nothing is."""
        volume, settings = state.frame_inputs(state.renderer, state.settings)
        tf, camera, bounds = (
            state.drawn_transfer_function,
            state.camera,
            state.shown_bounds,
        )  # by label where drawn
        if volume is None or tf is None or camera is None or bounds is None:
            raise VolrenError("nothing to render: open a volume first")
        if width < 1 or height < 1:
            raise VolrenError(f"a screenshot needs a positive size, got {width} x {height}")
        return cls(
            Path(path),
            int(width),
            int(height),
            state.renderer,
            volume,
            tf.copy(),
            settings,
            camera,
            state.background,
            tuple(bounds),
        )


def check_writable(path: PathArg) -> None:
    """Fail before rendering (which may take long) when the PNG cannot go there."""
    check_output(path)


def _still_frame_settings(settings: RenderSettings, renderer: Renderer) -> RenderSettings:
    return still_settings(settings, renderer.capabilities)


def _job_scene(job: ScreenshotJob) -> Scene:
    """The view's snapshot as a scene: its renderer and settings as they are (no quality level)."""
    return Scene(None, job.tf, job.camera, job.settings, renderer=job.renderer, size=(job.width, job.height),
                 volume=job.volume)  # fmt: skip


def _preparation(factory: RendererFactory) -> Preparation:
    """Renderers made by the app's `factory`, each given a still frame's settings (`still_settings`)."""
    return Preparation(factory, _still_frame_settings)


def job_drawing(job: ScreenshotJob, factory: RendererFactory = _registry_factory) -> Drawing:
    """`job` as `volren.draw` draws it (the movie export keeps its renderer for every frame)."""
    return Drawing(VolumeInput(job.volume), _job_scene(job), how=_preparation(factory))


def render_job(
    job: ScreenshotJob, factory: RendererFactory = _registry_factory, progress: ProgressCallback | None = None
) -> NDArray[np.float32]:
    """The premultiplied RGBA frame of `job`, from a renderer made for it and released after."""
    return draw(
        VolumeInput(job.volume), _job_scene(job), job.camera, progress, how=_preparation(factory)
    ).image


def write_job(job: ScreenshotJob, image: NDArray[np.float32]) -> None:
    """The frame as PNG over the job's background."""
    from volren.io import save_image

    save_image(image, job.path, job.background)


class Screenshotter(BackgroundJobs):
    """Renders and writes `ScreenshotJob`s one at a time in the background (see `BackgroundJobs`)."""

    def __init__(self, factory: RendererFactory = _registry_factory, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._factory = factory

    def start(self, job: ScreenshotJob) -> int:
        """Render and write `job` in the background; returns its serial."""

        def work(progress: ProgressCallback) -> str:
            image = render_job(job, self._factory, progress)
            progress(1.0)  # the last chance to cancel before the file is written
            write_job(job, image)
            return str(job.path)

        return self.start_work(work)
