"""Movies: a scene rendered frame by frame along an `Animation` and written as MP4 or GIF.

One renderer is prepared once and kept for every frame; it is given a new TF only on frames
whose TF differs (so a movie without TF keyframes builds its tables once), and new settings only
where that TF's class (`volren.model.tf_class`: smooth, sharp, band) asks for others: at a
quality level, each frame is drawn with the level's settings for its own TF's class. Each frame
is what `volren render` gives for the same camera and TF, converted to 8 bits exactly as its PNG is
(`volren.io.image_io.to_png_pixels`), so a lossless movie decodes to those PNGs' pixels.
"""

from __future__ import annotations

import statistics
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from volren.draw import Drawing, FrameData, VolumeInput, resolve_scene
from volren.draw.frame import draw_prepared
from volren.errors import VolrenError
from volren.io.image_io import to_png_pixels
from volren.io.movie_io import movie_writer
from volren.model.animation import Animation, View
from volren.model.clip_region import NO_CLIP
from volren.model.scene import Scene
from volren.model.scene_class import SceneClass
from volren.model.settings import RenderSettings
from volren.model.transfer_function_2d import TransferFunction
from volren.model.volume import Volume
from volren.quality import AUTO, at_level
from volren.renderers.base import ProgressCallback, Renderer

if TYPE_CHECKING:
    from volren.bricked.source import BrickSource


@dataclass(frozen=True)
class MovieResult:
    path: Path
    frames: int
    width: int
    height: int
    fps: float
    median_frame_ms: float
    total_ms: float


def render_movie(
    scene: Scene,
    animation: Animation,
    path: str | Path,
    background: Sequence[float] = (0.0, 0.0, 0.0),
    lossless: bool = False,
    progress: ProgressCallback | None = None,
    steps: Sequence[str | Path] | None = None,
    source: BrickSource | None = None,
    bounds: Sequence[float] | None = None,
    level: str | None = None,
) -> MovieResult:
    """Render `scene` (with its volume loaded) along `animation` into `path` (.mp4 or .gif), the
    frames over `background`. A scene's renderer `auto` becomes the fastest measured one at
    quality `default`, with the scene's settings as they are. `level`: the quality level the
    scene's settings are at, so that frames whose TF is of another class get that level's
    settings for it (`record_movie`). `progress(fraction of the movie)` may raise to stop: then
    no file is left (and an older one of that name is kept).

    `steps`: the files of a time series (the scene's volume is the first): the movie runs through
    them in order, spread evenly over its frames, each read when its first frame comes, with the
    camera placed on the first step's bounds throughout.

    `source`: a level too large for memory (`volren.bricked`), streamed brick by brick for every
    frame; the scene's volume then only stands in for it. `bounds` place the camera (default: the
    scene volume's; an OME-Zarr image's full resolution, so that the level drawn does not move it)."""
    volume = scene.volume
    if volume is None:
        raise VolrenError("the scene has no volume to make a movie of")
    if scene.renderer == AUTO:
        place = bounds or volume.bounds
        cameras = [
            animation.camera(i, scene.camera, place, scene.size[0] / scene.size[1])
            for i in range(animation.frames)
        ]
        clipped = scene.settings.clip
        choosing = replace(scene, settings=scene.settings.with_(clip=animation.clips_anywhere(clipped)))
        scene, _ = resolve_scene(choosing, VolumeInput(volume), None, cameras=cameras)
        scene = replace(scene, settings=scene.settings.with_(clip=clipped))
    volumes = None if not steps else _step_volumes(steps, animation.frames, scene.scalars)
    with Drawing(VolumeInput(volume), scene) as drawing:
        return record_movie(drawing.renderer, animation, scene.camera, scene.transfer_function, bounds or volume.bounds,
                            scene.size, path, background, lossless, progress, scene.renderer, volumes, source,
                            level)  # fmt: skip


def _check_views(renderer: Renderer, animation: Animation, start_view: View, bounds: Sequence[float], aspect: float,
                 label: str | None) -> None:  # fmt: skip
    """A one-line error before the first frame when the renderer cannot draw some frame's view (an
    eye inside the volume, a clipping plane through it: `Capabilities.camera_reason`), rather than
    after minutes of frames."""
    capabilities = getattr(renderer, "capabilities", None)
    volume = getattr(renderer, "volume", None)
    if capabilities is None or volume is None:
        return
    for index in range(animation.frames):
        reason = capabilities.camera_reason(
            volume.kind, animation.camera(index, start_view, bounds, aspect), volume.bounds
        )
        if reason:
            name = label or getattr(renderer, "name", "the renderer")
            raise VolrenError(f"movie frame {index + 1} of {animation.frames}: renderer {name} {reason}")


#: settings(volume, tf) -> the settings a frame showing `volume` with `tf` is drawn with.
SettingsByClass = Callable[[Volume, TransferFunction], RenderSettings]


def _settings_by_class(renderer: Renderer, name: str | None, level: str | None,
                       start_tf: TransferFunction) -> SettingsByClass | None:  # fmt: skip
    """At quality `level`, each frame's settings: the level's for its own TF's class. None (the
    renderer's settings for every frame) without a level, or where the settings are not exactly the
    level's for `start_tf`'s class: settings the user gave stay as they are."""
    volume, settings = getattr(renderer, "volume", None), getattr(renderer, "settings", None)
    if level is None or name is None or volume is None or settings is None:
        return None
    if at_level(name, SceneClass.of(volume, start_tf), level, settings) != settings:
        return None

    def settings_of(frame_volume: Volume, tf: TransferFunction) -> RenderSettings:
        return at_level(name, SceneClass.of(frame_volume, tf), level, settings) or settings

    return settings_of


def _step_volumes(
    steps: Sequence[str | Path], frames: int, scalars: str | None
) -> Callable[[int], Volume | None]:
    """Frame i's time step, read when it first comes (None: the frame before's step still)."""
    from volren.io import load_volume

    shown: list[int] = [0]  # the scene's volume is step 0

    def volume_at(index: int) -> Volume | None:
        step = min(index * len(steps) // frames, len(steps) - 1)
        if step == shown[0]:
            return None
        shown[0] = step
        return load_volume(steps[step], scalars=scalars)

    return volume_at


def record_movie(
    renderer: Renderer,
    animation: Animation,
    start_view: View,
    start_tf: TransferFunction,
    bounds: Sequence[float],
    size: tuple[int, int],
    path: str | Path,
    background: Sequence[float] = (0.0, 0.0, 0.0),
    lossless: bool = False,
    progress: ProgressCallback | None = None,
    label: str | None = None,
    volumes: Callable[[int], Volume | None] | None = None,
    source: BrickSource | None = None,
    level: str | None = None,
) -> MovieResult:
    """The movie from a renderer that holds the volume, settings and `start_tf` (the app brings its
    own): the orbit starts at `start_view`; TF keyframes replace `start_tf` where they are;
    `volumes(i)`, where given, is the volume frame i shows when it is another than the frame
    before's (a time series); `source`, where given, is streamed brick by brick for each frame
    (`volren.draw.frame.draw_prepared`; the renderer's volume stands in for it). `level`: the quality level the renderer's settings are at for
    `start_tf`'s class (`label` names the renderer); a frame whose TF is of another class gets
    the level's settings for that class (`_settings_by_class`)."""
    width, height = size
    frames = animation.frames
    times: list[float] = []
    tf = start_tf
    settings_of = _settings_by_class(renderer, label or getattr(renderer, "name", None), level, start_tf)
    settings = getattr(renderer, "settings", None)
    start_clip = settings.clip if settings is not None else NO_CLIP
    frame_data = FrameData(source=source)
    if source is None:
        _check_views(renderer, animation, start_view, bounds, width / height, label)
    with movie_writer(path, animation.fps, lossless) as writer:
        for index in range(frames):
            volume = volumes(index) if volumes is not None else None
            if volume is not None:
                renderer.set_volume(volume)
            frame_tf = animation.transfer_function(index, start_tf)
            if settings_of is not None and (frame_tf is not tf or volume is not None):
                frame_settings = settings_of(renderer.volume, frame_tf)  # type: ignore[attr-defined]
                if frame_settings != settings:  # only where the class changes: no new tables between
                    renderer.set_settings(frame_settings)
                    settings = frame_settings
            if frame_tf is not tf:
                renderer.set_transfer_function(frame_tf)
                tf = frame_tf
            if animation.clip_keys:  # planes move between keyframes: two numbers per ray, no tables
                current = renderer.settings  # type: ignore[attr-defined]
                frame_clip = animation.clip(index, start_clip)
                if frame_clip != current.clip:
                    renderer.set_settings(current.with_(clip=frame_clip))
            camera = animation.camera(index, start_view, bounds, width / height)
            within = None if progress is None else _within_frame(progress, index, frames)
            image, stats, _ = draw_prepared(renderer, frame_data, tf, camera, width, height, within, label)
            times.append(stats.ms)
            writer.append(to_png_pixels(image, background))
            if progress is not None:
                progress((index + 1) / frames)
    return MovieResult(Path(path), frames, width, height, animation.fps, statistics.median(times), sum(times))


def _within_frame(progress: ProgressCallback, index: int, frames: int) -> ProgressCallback:
    """A renderer's progress through frame `index` as progress through the movie."""
    return lambda fraction: progress((index + min(max(fraction, 0.0), 1.0)) / frames)
