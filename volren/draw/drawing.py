"""The one path from a scene to pixels: `auto` and the quality level resolved (`resolve_scene`),
the scene checked (`check_scene`), a renderer prepared, and each frame drawn the way its input
asks (`volren.draw.frame`): whole, streamed brick by brick, or on a cluster.

`volren.render`, `volren render`, `volren movie` and the app's screenshots and movies all draw
through a `Drawing`. Used as a context manager, a `Drawing` keeps the renderer it prepared for
the frames after the first: a new camera is only a new frame, a TF edit only the renderer's
`set_transfer_function` (its tables), never a new set-up of the volume.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator, Sequence
from contextlib import AbstractContextManager, ExitStack, contextmanager, nullcontext
from dataclasses import replace
from types import TracebackType

from volren.draw.frame import Drawn, draw_on_cluster, draw_prepared
from volren.draw.inputs import DrawInput, FrameData
from volren.draw.prepared import FROM_REGISTRY, Preparation, prepare
from volren.errors import VolrenWarning
from volren.model.camera import Camera
from volren.model.channels import ChannelTransferFunction
from volren.model.labels import LabelTransferFunction
from volren.model.scene import Scene
from volren.model.settings import RenderSettings, check_step
from volren.model.tf_coverage import coverage_problem
from volren.model.transfer_function_2d import TransferFunction
from volren.model.volume import Volume
from volren.quality import DEFAULT_LEVEL
from volren.renderers.base import ProgressCallback, Renderer


def resolve_scene(scene: Scene, source: DrawInput, level: str | None, cameras: Sequence[Camera] | None = None,
                  on_cluster: bool = False) -> tuple[Scene, str | None]:  # fmt: skip
    """`scene` with its renderer resolved (`auto`: the fastest measured one that draws it: bricks
    for an OME-Zarr image or a cluster, every one of `cameras`, default the scene's own) and its
    settings at quality `level` (as they are when None); and why `auto` chose (`volren.quality`). A
    scene drawn with a TF per label (`LabelTransferFunction`) is one of the volume kind's class,
    drawn by a renderer that draws labels; one with a TF per channel (`ChannelTransferFunction`),
    by a renderer that mixes channels."""
    from volren.model.scene_class import SceneClass
    from volren.quality import resolve

    volume = scene.volume if scene.volume is not None else source.stand_in()
    bounds = source.bounds
    views = tuple(cameras) if cameras is not None else (scene.resolved_camera(bounds),)
    tf = scene.transfer_function
    renderer, settings, why = resolve(SceneClass.of(volume, tf), tf.dims, scene.renderer, level, scene.settings,
                                      source.bricks or on_cluster, cameras=views, bounds=bounds,
                                      labels=isinstance(tf, LabelTransferFunction),
                                      channels=isinstance(tf, ChannelTransferFunction))  # fmt: skip
    return replace(scene, renderer=renderer, settings=settings), why


def check_scene(
    volume: Volume,
    tf: TransferFunction | LabelTransferFunction | ChannelTransferFunction,
    settings: RenderSettings,
    tf_name: str | None = None,
    step_name: str = "render setting step",
) -> None:
    """What `volren render` and `volren.render` check before drawing, so that bad input is an error
    or a warning instead of a black image and success: a step too small to honour (an error naming
    it as `step_name`), and a TF that shows nothing of the data (a VolrenWarning naming `tf_name`,
    the TF file, where there is one). With a TF per label, the TFs of the labels that occur are
    checked: a warning when none of them shows anything; with a TF per channel, each shown
    channel's TF over its own values."""
    check_step(settings.step, volume.bounds, volume.characteristic_length, step_name)
    if isinstance(tf, LabelTransferFunction):
        problem = _labels_problem(tf, volume)
    elif isinstance(tf, ChannelTransferFunction):
        problem = _channels_problem(tf, volume)
    else:
        problem = coverage_problem(tf, volume.value_range)
    if problem:
        warnings.warn(f"{tf_name or 'transfer function'}: {problem}", VolrenWarning, stacklevel=2)


def _labels_problem(tf: LabelTransferFunction, volume: Volume) -> str | None:
    """Why a TF per label shows nothing of `volume`: every label that occurs hidden, or each of
    their TFs showing nothing (the first label's reason); None when some label shows."""
    label_map = getattr(volume, "labels", None)
    present = label_map.present if label_map is not None else (0,)
    drawn = [(label, t) for label in present if (t := tf.effective_tf(label)) is not None]
    if not drawn:
        return "every label in the label volume is hidden, so the image is black"
    problems = [(label, coverage_problem(t, volume.value_range)) for label, t in drawn]
    if all(problem for _, problem in problems):
        label, problem = problems[0]
        return f"no label shows anything; label {label}: {problem}"
    return None


def _channels_problem(tf: ChannelTransferFunction, volume: Volume) -> str | None:
    """Why a TF per channel shows nothing of `volume`: every channel hidden or weighted 0, or each
    shown channel's TF showing nothing of that channel's values (the first one's reason)."""
    channels = getattr(volume, "channels", None)
    drawn = [c for c in range(tf.count) if tf.drawn_weight(c) > 0]
    if not drawn:
        return "every channel is hidden or weighted 0, so the image is black"
    if channels is None or channels.count != tf.count:
        return None  # refused by the renderer, in its words
    problems = [(c, coverage_problem(tf.tfs[c], channels.value_ranges[c])) for c in drawn]
    if all(problem for _, problem in problems):
        c, problem = problems[0]
        return f"no channel shows anything; channel {channels.names[c]!r}: {problem}"
    return None


class Watch:
    """How a caller follows a frame: its stages timed (`volren render --timings`) and its progress
    shown. This one times nothing and hands every frame the one progress callback it was given."""

    def __init__(self, progress: ProgressCallback | None = None) -> None:
        self._progress = progress

    def stage(self, name: str) -> AbstractContextManager[object]:
        """A block of one stage: "load" (a level read), "set-up" (the renderer prepared), "frame"."""
        return nullcontext()

    def progress(self, label: str) -> AbstractContextManager[ProgressCallback | None]:
        """The progress callback of a frame described by `label` ("slicer 512x512")."""
        return nullcontext(self._progress)


class Drawing:
    """A scene ready to be drawn from its input: the renderer and settings final (`resolve_scene`),
    `quality` the level that picks an OME-Zarr image's level (`ZarrInput.frame`). `cluster`
    ("local", "local:N") or `scheduler` (an address) draws on dask.distributed. `how` makes and feeds
    the renderer (`Preparation`; the app brings its own).

    Each `frame` outside a ``with`` block prepares a renderer and releases it. Inside one, the
    renderer prepared for the first frame is kept for the next ones, and released at the end (an
    OME-Zarr image read whole gives it the level each view needs; a cluster frame is the cluster's)."""

    def __init__(self, source: DrawInput, scene: Scene, quality: str = DEFAULT_LEVEL, cluster: str | None = None,
                 scheduler: str | None = None, how: Preparation = FROM_REGISTRY) -> None:  # fmt: skip
        self.source = source
        self.scene = scene if scene.volume is not None else scene.with_volume(source.stand_in())
        self.quality = quality
        self.cluster = cluster
        self.scheduler = scheduler
        self.how = how
        self._keep = False
        self._renderer: Renderer | None = None
        self._volume: Volume | None = None  # what the kept renderer holds

    @property
    def on_cluster(self) -> bool:
        """Whether frames are drawn on a cluster (an empty --cluster is refused, not ignored)."""
        return self.cluster is not None or self.scheduler is not None

    def check(self, tf_name: str | None = None, step_name: str = "render setting step") -> None:
        """`check_scene` on the volume the scene is set up on."""
        assert self.scene.volume is not None
        check_scene(self.scene.volume, self.scene.transfer_function, self.scene.settings, tf_name, step_name)

    def camera(self) -> Camera:
        """The scene's camera, an orbit placed on the input's bounds (an OME-Zarr image's full
        resolution, whatever level is drawn)."""
        return self.scene.resolved_camera(self.source.bounds)

    def orbit(
        self, azimuth: float = 0.0, elevation: float = 0.0, zoom: float = 1.0, parallel: bool = False
    ) -> Camera:
        """The orbit view (reset on the input's bounds, then azimuth, elevation, zoom: the camera
        contract) at the scene's aspect ratio."""
        width, height = self.scene.size
        return Camera.orbit(self.source.bounds, azimuth, elevation, zoom, parallel, width / height)

    # ------------------------------------------------------------------ kept renderer
    def __enter__(self) -> Drawing:
        self._keep = True
        return self

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self._keep = False
        self.release()

    def release(self) -> None:
        """Release the kept renderer (a later frame prepares a new one)."""
        renderer, self._renderer, self._volume = self._renderer, None, None
        if renderer is not None:
            renderer.release()

    @property
    def renderer(self) -> Renderer:
        """The kept renderer, prepared with the scene's volume now if it is not yet (inside a
        ``with`` block only)."""
        if not self._keep:
            raise RuntimeError("a Drawing keeps its renderer only inside a with block")
        return self._prepared(self.scene.volume)  # type: ignore[arg-type]

    def set_transfer_function(
        self, tf: TransferFunction | LabelTransferFunction | ChannelTransferFunction
    ) -> None:
        """Draw the next frames with `tf`: the kept renderer gets it (its TF tables), nothing else
        is prepared again. The renderer and settings stay those chosen for the scene's TF."""
        self.scene = replace(self.scene, transfer_function=tf)
        if self._renderer is not None:
            self._renderer.set_transfer_function(tf)

    def _prepared(self, volume: Volume) -> Renderer:
        if self._renderer is not None and volume is not self._volume:
            self._renderer.set_volume(volume)  # another level of an OME-Zarr image
            self._volume = volume
        if self._renderer is None:
            scene = self.scene
            self._renderer = prepare(
                scene.renderer, volume, scene.transfer_function, scene.settings, self.how
            )
            self._volume = volume
        return self._renderer

    @contextmanager
    def _renderer_for(self, volume: Volume) -> Iterator[Renderer]:
        """The kept renderer holding `volume`, or (outside a ``with`` block) a new one released after."""
        if self._keep:
            yield self._prepared(volume)
            return
        renderer = prepare(
            self.scene.renderer, volume, self.scene.transfer_function, self.scene.settings, self.how
        )
        try:
            yield renderer
        finally:
            renderer.release()

    # ------------------------------------------------------------------ frames
    def frame(self, camera: Camera | None = None, progress: ProgressCallback | None = None,
              size: tuple[int, int] | None = None, watch: Watch | None = None) -> Drawn:  # fmt: skip
        """One frame for `camera` (default: the scene's) at `size` (default: the scene's): (float32
        (H, W, 4) premultiplied RGBA, its FrameStats, what was drawn: a level, bricks, workers)."""
        scene = self.scene
        camera = camera or self.camera()
        width, height = size or scene.size
        watch = watch or Watch(progress)
        if self.on_cluster:
            assert not isinstance(
                scene.transfer_function, LabelTransferFunction | ChannelTransferFunction
            )  # refused by `volren.draw.labelled`'s and `volren.draw.channels`' callers
            with watch.stage("frame"), watch.progress(f"{scene.renderer} {width}x{height} bricks") as within:
                return draw_on_cluster(self.cluster, self.scheduler, self.source, scene.renderer, scene.settings,
                                       scene.transfer_function, camera, width, height, within, self.quality)  # fmt: skip
        if self.source.bricks:
            with watch.stage("load"):
                data = self.source.frame(scene.renderer, camera, width, height, self.quality)
        else:
            data = FrameData(volume=scene.volume)
        with ExitStack() as stack:
            with watch.stage("set-up"):
                renderer = stack.enter_context(self._renderer_for(data.volume or scene.volume))  # type: ignore[arg-type]
            with watch.stage("frame"), watch.progress(f"{scene.renderer} {width}x{height}") as within:
                return draw_prepared(renderer, data, scene.transfer_function, camera, width, height, within,
                                     label=scene.renderer)  # fmt: skip


def draw(source: DrawInput, scene: Scene, camera: Camera | None = None, progress: ProgressCallback | None = None,
         quality: str = DEFAULT_LEVEL, cluster: str | None = None, scheduler: str | None = None,
         how: Preparation = FROM_REGISTRY) -> Drawn:  # fmt: skip
    """One frame of `scene` (renderer and settings final) from `source`: `Drawing(...).frame(...)`."""
    return Drawing(source, scene, quality, cluster, scheduler, how).frame(camera, progress)
