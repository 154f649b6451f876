"""Files <-> what the app shows (no Qt): `load_input` returns a `LoadedInput`; `view_scene` is
the way back, the `Scene` that File > Save Scene writes.

The app opens three kinds of input: a volume (file or DICOM folder), a scene JSON (volume, TF,
camera, settings and renderer together), and a transfer-function JSON on its own, which is
applied to the volume already shown (so dropping a TF file onto the window just works). With no
input the bundled Marschner-Lobb sample opens with its TF.

This runs in a worker thread, so it only builds model objects; the camera is resolved later,
when the viewport's aspect ratio is known. It also does the preparation renderers would
otherwise do on their first frame, in the render thread, without feedback: a tetrahedral mesh's
face adjacency (`prepare_mesh`: about 2 s for 513k tets the first time, 0.1 s from its disk cache,
then free from its memory cache) and its mean edge length. `progress(stage, fraction)` hears
which stage runs (fraction None: unknown); raising from it (`LoadCancelled`) stops the load
between stages.

Scenes carry two optional keys of the app's own besides DESIGN.md's fields, `crop` (six numbers)
and `background` (r, g, b in [0, 1]); `Scene` keeps unknown keys in `extra`, so other readers
ignore them. A scene saved on a step of a time series names the series and the step
(`volren.model.scene.TIME_SERIES_KEY`): it reopens as that series, at that step. A scene with
labels (Real-Time Volume Graphics, chapter 16) brings its label volume, read onto the volume, and
its TF per label, whose base becomes the TF shown (the one the 1D editor edits).
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING, Any

from volren.errors import VolrenError, file_error
from volren.model.camera import Camera
from volren.model.channels import ChannelTransferFunction
from volren.model.crop import Box, check_box
from volren.model.labels import LabelTransferFunction
from volren.model.scene import TIME_SERIES_KEY, OrbitView, Scene
from volren.model.settings import RenderSettings
from volren.model.transfer_function_2d import TransferFunction
from volren.model.volume import TetVolume, UniformVolume, Volume

if TYPE_CHECKING:
    from volren.io.series_io import TimeSeries

DEFAULT_SAMPLE = "marschner_lobb"

PathArg = str | PathLike[str]
RGB = tuple[float, float, float]
#: progress(stage text, fraction done or None when unknown); may raise to stop the load.
Progress = Callable[[str, float | None], None]

#: The scene keys of the app's own (kept by `Scene.extra`, ignored by other readers).
CROP_KEY = "crop"
BACKGROUND_KEY = "background"


class LoadCancelled(Exception):
    """Raised from a `Progress` callback: nobody wants this load any more."""


@dataclass(frozen=True)
class LoadedInput:
    """What one file (or the default sample) contributes; `volume is None` for a TF-only file.

    `volume_path` is the file the volume came from (absolute; None for a volume made in memory),
    so that a scene saved later can refer to it; `source` is only its name for titles. A scene
    saved on a time series gives the `series` and the `step` its volume is.
    """

    volume: Volume | None
    transfer_function: TransferFunction | None
    camera: Camera | OrbitView | None = None
    settings: RenderSettings | None = None
    renderer: str | None = None
    source: str = ""
    volume_path: str | None = None
    scalars: str | None = None
    crop: Box | None = None
    background: RGB | None = None
    series: TimeSeries | None = None
    step: int = 0
    #: a scene's TF per label (its base is `transfer_function`), for a volume with labels
    label_tf: LabelTransferFunction | None = None
    #: the file the volume's labels came from (absolute), for a scene saved later
    labels_path: str | None = None

    def resolve_camera(self, aspect: float) -> Camera | None:
        """The explicit camera, or the orbit description fitted to the viewport; None: app default."""
        if isinstance(self.camera, Camera) or self.camera is None:
            return self.camera
        if self.volume is None:
            return None
        return self.camera.camera(self.volume.bounds, aspect)


def _io():
    """volren.io, imported late: the app starts (and the CLI parses) without loading readers."""
    from volren import io

    return io


def _is_scene_json(path: Path) -> bool:
    """A scene names a volume or holds an inline TF; anything else JSON is read as a TF."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return True  # let the scene reader word the error
    return isinstance(data, dict) and ("volume" in data or "transfer_function" in data)


def _quiet(stage: str, fraction: float | None) -> None:
    """The `Progress` of loads nobody watches."""


def prepare_for_rendering(volume: Volume, progress: Progress = _quiet) -> None:
    """Do now, in the loading thread, the per-volume work the renderers cache (see the module
    docstring), so the first frame does not stall the render thread without feedback."""
    if isinstance(volume, TetVolume):
        from volren.model.tet_mesh import prepare_mesh

        progress("Preparing mesh…", None)
        prepare_mesh(volume)
        volume.mean_edge_length  # noqa: B018 - a cached property: computed here, once
    from volren.app.core.joint_histogram import gradient_stats
    from volren.model.value_histogram import value_histogram

    progress("Histograms…", None)
    value_histogram(volume)  # what the 1D editor draws first (cached per volume)
    gradient_stats(volume)  # the 2D editor's gradient axis (cached per volume)


def load_input(
    path: PathArg | None = None,
    tf: PathArg | None = None,
    scalars: str | None = None,
    raw: Mapping[str, Any] | None = None,
    progress: Progress = _quiet,
) -> LoadedInput:
    """Read `path` (default: the bundled sample) and optionally a TF file that overrides its TF;
    `raw`: the layout of a headerless raw file (`load_volume`'s shape, dtype, byte_order, spacing,
    header_bytes)."""
    io = _io()
    override = None
    if tf is not None:
        progress(f"Reading {Path(tf).name}…", None)
        override = io.load_transfer_function(tf)
    if path is None:
        from volren.samples import sample_paths

        volume_path, tf_path = sample_paths(DEFAULT_SAMPLE)
        progress(f"Reading sample {DEFAULT_SAMPLE}…", None)
        volume = io.load_volume(volume_path, scalars=scalars)
        prepare_for_rendering(volume, progress)
        return LoadedInput(
            volume,
            override or io.load_transfer_function(tf_path),
            source=f"sample {DEFAULT_SAMPLE}",
            volume_path=os.path.abspath(volume_path),
            scalars=scalars,
        )
    p = Path(path)
    progress(f"Reading {p.name or p}…", None)
    if p.suffix.lower() == ".json" and p.is_file():
        if _is_scene_json(p):
            return _load_scene(p, override, progress)
        return LoadedInput(None, io.load_transfer_function(p), source=p.name)
    if scalars is None and not raw:
        volume = _read_with_channels(p, progress)
    else:
        volume = io.load_volume(p, scalars=scalars, **dict(raw or {}))
    prepare_for_rendering(volume, progress)
    if override is None:
        from volren.api import default_transfer_function

        override = default_transfer_function(volume)
    return LoadedInput(
        volume, override, source=p.name or str(p), volume_path=os.path.abspath(p), scalars=scalars
    )


def _read_with_channels(path: Path, progress: Progress) -> Volume:
    """The volume in `path`, with every channel where it has several (an OME-Zarr image's c axis, an
    array of several components), as napari's and OMERO's channel lists show them: each channel a
    TF of its own (Max 1995, section 2), named, coloured and windowed as the file says
    (`volren.io.omero_channels`). The first `MAX_CHANNELS` of an image with more, with a note."""
    io = _io()
    from volren.io.ome_zarr_io import is_ome_zarr, open_multiscale
    from volren.model.channels import MAX_CHANNELS

    if is_ome_zarr(path):
        count = open_multiscale(path, channels_ok=True).channel_count
        if count > 1:
            pick: bool | list[int] = True if count <= MAX_CHANNELS else list(range(MAX_CHANNELS))
            volume = io.load_volume(path, channels=pick)
            if count > MAX_CHANNELS:
                note = f"{path.name}: {count} channels; the first {MAX_CHANNELS} are drawn (volren --channels picks others)"
                volume = replace(volume, notes=(*volume.notes, note))
            return volume  # type: ignore[no-any-return]
        return io.load_volume(path)  # type: ignore[no-any-return]
    volume = io.load_volume(path)
    scalars = getattr(volume, "scalars", None) or ""
    if isinstance(volume, UniformVolume) and scalars.endswith(":magnitude"):  # an array of several components
        progress(f"Reading the channels of {path.name}…", None)
        try:
            return io.load_volume(path, channels=True)  # type: ignore[no-any-return]
        except VolrenError:  # more components than are drawn at once: the magnitude, as before
            return volume
    return volume  # type: ignore[no-any-return]


def _load_scene(path: Path, override: TransferFunction | None, progress: Progress) -> LoadedInput:
    """A scene with its volume (read as a stage of its own: it is the slow part)."""
    io = _io()
    scene = io.load_scene(path, load_volume=False)
    if scene.volume_path is None:
        raise VolrenError(f"{path}: the scene names no volume")
    crop, background = _view_extras(scene.extra, path)
    progress(f"Reading {Path(scene.volume_path).name}…", None)
    try:
        volume = io.load_volume(scene.volume_path, scene.scalars, channels=scene.channels)
    except VolrenError as exc:  # worded as volren.io.load_scene words it
        raise file_error(path, f"volume: {exc}") from None
    prepare_for_rendering(volume, progress)
    series, step = io.scene_time_series(scene) or (None, 0)
    tf: TransferFunction = scene.transfer_function  # type: ignore[assignment]  # a TF per label: below; per
    # channel: `ViewState.load` takes it for the volume's channels
    label_tf = None
    if isinstance(scene.transfer_function, LabelTransferFunction):  # over the base the 1D editor edits
        tf, label_tf = scene.transfer_function.base, scene.transfer_function
    labels_path = None
    if scene.labels_path is not None:
        volume = _with_labels(path, scene.labels_path, volume, progress)
        labels_path = os.path.abspath(scene.labels_path)
    return LoadedInput(
        volume,
        override or tf,
        scene.camera,
        scene.settings,
        scene.renderer,
        source=path.name,
        volume_path=os.path.abspath(scene.volume_path),
        scalars=scene.scalars,
        crop=crop,
        background=background,
        series=series,
        step=step,
        label_tf=label_tf,
        labels_path=labels_path,
    )


def _with_labels(path: Path, labels_path: str, volume: Volume, progress: Progress) -> Volume:
    """`volume` with the scene's label volume read onto it (errors name the scene file)."""
    from volren.io.label_io import load_labels

    progress(f"Reading {Path(labels_path).name}…", None)
    if not isinstance(volume, UniformVolume):
        raise file_error(
            path, "labels: label volumes are for uniform grids; the scene's volume is a tetrahedral mesh"
        )
    try:
        return replace(volume, labels=load_labels(labels_path, volume))
    except VolrenError as exc:
        raise file_error(path, f"labels: {exc}") from None


def _view_extras(extra: Mapping[str, Any], path: Path) -> tuple[Box | None, RGB | None]:
    """The scene's optional crop box and background colour, checked (errors name the file)."""
    crop = background = None
    try:
        if extra.get(CROP_KEY) is not None:
            crop = check_box(extra[CROP_KEY])
        if extra.get(BACKGROUND_KEY) is not None:
            background = _rgb(extra[BACKGROUND_KEY])
    except VolrenError as exc:
        raise file_error(path, str(exc)) from None
    return crop, background


def _rgb(value: Any) -> RGB:
    bad = VolrenError(f"'{BACKGROUND_KEY}' must be [r, g, b] with each in [0, 1], got {value!r}")
    if not isinstance(value, Sequence) or isinstance(value, str) or len(value) != 3:
        raise bad
    try:
        r, g, b = (float(v) for v in value)
    except (TypeError, ValueError):
        raise bad from None
    if not all(math.isfinite(v) and 0.0 <= v <= 1.0 for v in (r, g, b)):
        raise bad
    return r, g, b


def view_scene(
    volume_path: PathArg,
    transfer_function: TransferFunction | LabelTransferFunction | ChannelTransferFunction,
    camera: Camera,
    settings: RenderSettings,
    renderer: str,
    size: tuple[int, int],
    *,
    scalars: str | None = None,
    crop: Box | None = None,
    background: RGB | None = None,
    time_series: tuple[PathArg, int] | None = None,
    labels_path: PathArg | None = None,
    channels: bool | tuple[int, ...] | None = None,
) -> Scene:
    """The `Scene` of what the app shows, for `volren.io.save_scene`; `load_input` reads it back
    (crop, background, the time series with its step, and the labels' file included); with labels,
    `transfer_function` is their TF per label; with `channels` (the file's channels read: True for
    all), their TF per channel."""
    extra: dict[str, Any] = {}
    if crop is not None:
        extra[CROP_KEY] = list(crop)
    if background is not None:
        extra[BACKGROUND_KEY] = list(background)
    if time_series is not None:
        extra[TIME_SERIES_KEY] = {"path": os.fspath(time_series[0]), "step": time_series[1]}
    return Scene(
        os.fspath(volume_path),
        transfer_function,
        camera,
        settings,
        scalars=scalars,
        renderer=renderer,
        size=(max(1, int(size[0])), max(1, int(size[1]))),
        extra=extra,
        labels_path=os.fspath(labels_path) if labels_path is not None else None,
        channels=channels,
    )


def one_line_error(exc: BaseException, path: PathArg | None = None) -> str:
    """The message people see: VolrenErrors as they are, anything else with its type and the file."""
    if isinstance(exc, VolrenError):
        return str(exc)
    text = " ".join(str(exc).split()) or type(exc).__name__
    if isinstance(exc, OSError | ValueError | KeyError):
        return f"{path}: {text}" if path is not None else text
    prefix = f"{path}: " if path is not None else ""
    return f"{prefix}{type(exc).__name__}: {text}"
