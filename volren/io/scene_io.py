"""Scene files (model.scene's JSON) with paths relative to the scene file.

A scene refers to its volume by path, and may refer to its transfer function by path instead of
holding it inline; both are resolved against the scene file's folder, so a folder of scenes and
data can be moved as a whole. Saving writes the volume path relative to the scene's folder and
the transfer function inline. A scene saved on a step of a time series names the series too
(`TIME_SERIES_KEY`, relative in the same way): its step's file is the volume read. A scene's
label volume (``volume.labels``) is a path relative in the same way, read onto the volume
(`volren.io.label_io.load_labels`) when the volume is. A scene's channel pick (``volume.channels``)
is read with the volume (`load_volume`'s `channels`).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import replace
from pathlib import Path

from volren.errors import VolrenError, file_error
from volren.io.json_text import read_json, write_json
from volren.io.label_io import load_labels
from volren.io.series_io import TimeSeries, load_series
from volren.io.tf_io import load_transfer_function, tf_from_data
from volren.io.volume_io import load_volume as _load_volume
from volren.model.scene import TIME_SERIES_KEY, Scene
from volren.model.volume import UniformVolume


def _resolve(folder: Path, relative: str) -> str:
    path = Path(relative).expanduser()
    return os.path.normpath(path if path.is_absolute() else folder / path)


def load_scene(path: str | Path, load_volume: bool = True) -> Scene:
    """Read a scene; with `load_volume` the volume is loaded too (errors name the scene file)."""
    path = Path(path)
    data = read_json(path)
    if not isinstance(data, Mapping):
        raise file_error(path, f"a scene must be a JSON object, got {type(data).__name__}")
    data = dict(data)
    folder = path.parent
    tf = data.get("transfer_function")
    if isinstance(tf, str):
        try:
            data["transfer_function"] = _tf_file_data(Path(_resolve(folder, tf)))
        except VolrenError as exc:
            raise file_error(path, f"transfer function: {exc}") from None
    _inline_keyframe_tfs(data, folder, path)
    _volume_from_series(data, folder, path)
    volume = data.get("volume")
    if isinstance(volume, Mapping) and isinstance(volume.get("path"), str):
        data["volume"] = volume = {**volume, "path": _resolve(folder, volume["path"])}
    if isinstance(volume, Mapping) and isinstance(volume.get("labels"), str):
        data["volume"] = {**volume, "labels": _resolve(folder, volume["labels"])}
    try:
        scene = Scene.from_dict(data)
    except VolrenError as exc:
        raise file_error(path, str(exc)) from None
    if load_volume and scene.volume_path is not None:
        try:
            scene = scene.with_volume(_load_volume(scene.volume_path, scene.scalars, channels=scene.channels))
        except VolrenError as exc:
            raise file_error(path, f"volume: {exc}") from None
        if scene.labels_path is not None:
            scene = scene.with_volume(_with_labels(path, scene))
    return scene


def _with_labels(path: Path, scene: Scene) -> UniformVolume:
    """The scene's volume with its label file read onto it (errors name the scene file)."""
    volume = scene.volume
    if not isinstance(volume, UniformVolume):
        raise file_error(
            path, "labels: label volumes are for uniform grids; the scene's volume is a tetrahedral mesh"
        )
    try:
        return replace(volume, labels=load_labels(scene.labels_path, volume))  # type: ignore[arg-type]
    except VolrenError as exc:
        raise file_error(path, f"labels: {exc}") from None


def _tf_file_data(path: Path) -> dict:
    """The inline form of a scene's TF file: a 1D or 2D TF or ParaView preset
    (`load_transfer_function`), a TF per label (kind "labels", `LabelTransferFunction`) or a TF
    per channel (kind "channels", `ChannelTransferFunction`)."""
    data = read_json(path)
    if isinstance(data, Mapping) and data.get("kind") in ("labels", "channels"):
        return dict(data)  # checked with the scene (`Scene.from_dict`)
    return tf_from_data(data, path).to_dict()


def _inline_keyframe_tfs(data: dict, folder: Path, path: Path) -> None:
    """The movie's TF keyframes given by path, read and held inline as the scene's own TF is."""
    movie = data.get("movie")
    keyframes = movie.get("keyframes") if isinstance(movie, Mapping) else None
    if not isinstance(keyframes, list):
        return  # a malformed movie is `Animation.from_dict`'s to report
    inlined = []
    for index, key in enumerate(keyframes):
        if isinstance(key, Mapping) and isinstance(key.get("transfer_function"), str):
            try:
                tf = load_transfer_function(_resolve(folder, key["transfer_function"]))
            except VolrenError as exc:
                raise file_error(path, f"movie: keyframe {index}: transfer function: {exc}") from None
            key = {**key, "transfer_function": tf.to_dict()}
        inlined.append(key)
    data["movie"] = {**movie, "keyframes": inlined}


def _is_step(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0


def _volume_from_series(data: dict, folder: Path, path: Path) -> None:
    """A scene saved on a time series: the series resolved against the scene's folder and
    checked, and its step's file made the scene's volume (errors name the scene file)."""
    entry = data.get(TIME_SERIES_KEY)
    if entry is None:
        return
    if (
        not isinstance(entry, Mapping)
        or not isinstance(entry.get("path"), str)
        or not _is_step(entry.get("step"))
    ):
        raise file_error(path, f"'{TIME_SERIES_KEY}' must be an object with a 'path' (a .pvd file or a folder of "
                               "volume files) and a 'step' (an integer from 0)")  # fmt: skip
    try:
        series = load_series(_resolve(folder, entry["path"]))
    except VolrenError as exc:
        raise file_error(path, f"time series: {exc}") from None
    step = entry["step"]
    if step >= len(series):
        raise file_error(
            path, f"time series step {step}: {series.source.name} has steps 0 to {len(series) - 1}"
        )
    data[TIME_SERIES_KEY] = {**entry, "path": str(series.source)}
    volume = data.get("volume") or {}
    if isinstance(volume, Mapping):  # anything else is `Scene.from_dict`'s to report
        data["volume"] = {**volume, "path": str(series.steps[step])}


def scene_time_series(scene: Scene) -> tuple[TimeSeries, int] | None:
    """The time series a scene read by `load_scene` was saved on, and its step (None: no series)."""
    entry = scene.extra.get(TIME_SERIES_KEY)
    if entry is None:
        return None
    return load_series(entry["path"]), entry["step"]


def _relative(target: str, folder: Path) -> str:
    """`target` relative to `folder` (absolute on another drive), with forward slashes."""
    target = os.path.abspath(target)
    try:
        relative = os.path.relpath(target, os.path.abspath(folder))
    except ValueError:  # another drive (Windows): keep it absolute
        relative = target
    return Path(relative).as_posix()


def save_scene(scene: Scene, path: str | Path) -> None:
    """Write a scene; the volume and time-series paths relative to the scene file's folder when
    possible."""
    path = Path(path)
    if not isinstance(scene, Scene):
        raise VolrenError(f"{path}: expected a Scene to save, got {type(scene).__name__}")
    data = scene.to_dict()
    if scene.volume_path is not None:
        data["volume"] = {**data["volume"], "path": _relative(scene.volume_path, path.parent)}
    if scene.labels_path is not None:
        data["volume"] = {**data["volume"], "labels": _relative(scene.labels_path, path.parent)}
    series = data.get(TIME_SERIES_KEY)
    if isinstance(series, Mapping) and isinstance(series.get("path"), str):
        data[TIME_SERIES_KEY] = {**series, "path": _relative(series["path"], path.parent)}
    write_json(data, path)
