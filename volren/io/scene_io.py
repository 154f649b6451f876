"""Scene files (model.scene's JSON) with paths relative to the scene file.

A scene refers to its volume by path, and may refer to its transfer function by path instead of
holding it inline; both are resolved against the scene file's folder, so a folder of scenes and
data can be moved as a whole. Saving writes the volume path relative to the scene's folder and
the transfer function inline.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path

from volren.errors import VolrenError, file_error
from volren.io.json_text import read_json, write_json
from volren.io.tf_io import load_transfer_function
from volren.io.volume_io import load_volume as _load_volume
from volren.model.scene import Scene


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
            data["transfer_function"] = load_transfer_function(_resolve(folder, tf)).to_dict()
        except VolrenError as exc:
            raise file_error(path, f"transfer function: {exc}") from None
    _inline_keyframe_tfs(data, folder, path)
    volume = data.get("volume")
    if isinstance(volume, Mapping) and isinstance(volume.get("path"), str):
        data["volume"] = {**volume, "path": _resolve(folder, volume["path"])}
    try:
        scene = Scene.from_dict(data)
    except VolrenError as exc:
        raise file_error(path, str(exc)) from None
    if load_volume and scene.volume_path is not None:
        try:
            scene = scene.with_volume(_load_volume(scene.volume_path, scene.scalars))
        except VolrenError as exc:
            raise file_error(path, f"volume: {exc}") from None
    return scene


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


def save_scene(scene: Scene, path: str | Path) -> None:
    """Write a scene; the volume path relative to the scene file's folder when possible."""
    path = Path(path)
    if not isinstance(scene, Scene):
        raise VolrenError(f"{path}: expected a Scene to save, got {type(scene).__name__}")
    data = scene.to_dict()
    if scene.volume_path is not None:
        volume = os.path.abspath(scene.volume_path)
        try:
            relative = os.path.relpath(volume, os.path.abspath(path.parent))
        except ValueError:  # another drive (Windows): keep it absolute
            relative = volume
        data["volume"] = {**data["volume"], "path": Path(relative).as_posix()}
    write_json(data, path)
