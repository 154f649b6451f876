"""Files -> what the app shows (no Qt): `load_input` returns a `LoadedInput`.

The app opens three kinds of input: a volume (file or DICOM folder), a scene JSON (volume, TF,
camera, settings and renderer together), and a transfer-function JSON on its own, which is
applied to the volume already shown (so dropping a TF file onto the window just works). With no
input the bundled Marschner-Lobb sample opens with its TF.

This runs in a worker thread, so it only builds model objects; the camera is resolved later,
when the viewport's aspect ratio is known.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from os import PathLike
from pathlib import Path

from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.scene import OrbitView
from volren.model.settings import RenderSettings
from volren.model.transfer_function_2d import TransferFunction
from volren.model.volume import Volume

DEFAULT_SAMPLE = "marschner_lobb"

PathArg = str | PathLike[str]


@dataclass(frozen=True)
class LoadedInput:
    """What one file (or the default sample) contributes; `volume is None` for a TF-only file."""

    volume: Volume | None
    transfer_function: TransferFunction | None
    camera: Camera | OrbitView | None = None
    settings: RenderSettings | None = None
    renderer: str | None = None
    source: str = ""

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


def load_input(
    path: PathArg | None = None,
    tf: PathArg | None = None,
    scalars: str | None = None,
) -> LoadedInput:
    """Read `path` (default: the bundled sample) and optionally a TF file that overrides its TF."""
    io = _io()
    override = io.load_transfer_function(tf) if tf is not None else None
    if path is None:
        from volren.samples import sample_paths

        volume_path, tf_path = sample_paths(DEFAULT_SAMPLE)
        volume = io.load_volume(volume_path, scalars=scalars)
        return LoadedInput(volume, override or io.load_transfer_function(tf_path), source=f"sample {DEFAULT_SAMPLE}")
    p = Path(path)
    if p.suffix.lower() == ".json" and p.is_file():
        if _is_scene_json(p):
            scene = io.load_scene(p)
            if scene.volume is None:
                raise VolrenError(f"{p}: the scene names no volume")
            return LoadedInput(
                scene.volume,
                override or scene.transfer_function,
                scene.camera,
                scene.settings,
                scene.renderer,
                source=p.name,
            )
        return LoadedInput(None, io.load_transfer_function(p), source=p.name)
    volume = io.load_volume(p, scalars=scalars)
    if override is None:
        from volren.api import default_transfer_function

        override = default_transfer_function(volume)
    return LoadedInput(volume, override, source=p.name or str(p))


def one_line_error(exc: BaseException, path: PathArg | None = None) -> str:
    """The message people see: VolrenErrors as they are, anything else with its type and the file."""
    if isinstance(exc, VolrenError):
        return str(exc)
    text = " ".join(str(exc).split()) or type(exc).__name__
    if isinstance(exc, OSError | ValueError | KeyError):
        return f"{path}: {text}" if path is not None else text
    prefix = f"{path}: " if path is not None else ""
    return f"{prefix}{type(exc).__name__}: {text}"
