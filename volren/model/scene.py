"""A scene: what to render (volume, transfer function), from where (camera) and how (settings).

Scene files are versioned JSON (see `Scene.to_dict`); the volume is referenced by path, the
transfer function is stored inline. Reading and writing files is `volren.io.scene_io`'s job.

A segmented volume (Real-Time Volume Graphics, chapter 16) names its label file beside the
volume's, ``"volume": {"path": ..., "labels": "seg.nii.gz"}``, and its transfer function is then a
TF per label (``"kind": "labels"``, `LabelTransferFunction.to_dict`). Both are additions: a scene
without labels is written as before, and every older scene reads as before, so the format's
version stays 1 (a volren that knows no labels refuses such a scene's TF kind by name).

A multi-channel volume (Max 1995, section 2: several media on one grid) names its channel pick
beside the volume's path, ``"volume": {"path": ..., "channels": true}`` (every channel) or
``[0, 2]`` (the file's channels 0 and 2), and its TF is then a TF per channel (``"kind":
"channels"``, `ChannelTransferFunction.to_dict`): an addition in the same way.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

from volren.errors import VolrenError
from volren.model.camera import Camera, check_zoom
from volren.model.channels import MAX_CHANNELS, ChannelTransferFunction
from volren.model.file_version import check_format_version
from volren.model.labels import LabelTransferFunction
from volren.model.settings import RenderSettings, is_finite
from volren.model.transfer_function_2d import TransferFunction, transfer_function_from_dict
from volren.model.volume import Volume

SCENE_FORMAT_VERSION = 1
#: A scene saved on a step of a time series names the series and the step shown:
#: `"time_series": {"path": "run.pvd", "step": 2}` (a .pvd file or a folder of volume files, the
#: step from 0). "volume.path" is still that step's file, for readers that know no series; volren
#: reads the step from the series (`volren.io.scene_io`). Kept in `Scene.extra`.
TIME_SERIES_KEY = "time_series"


@dataclass(frozen=True)
class OrbitView:
    """DESIGN.md's camera description: reset on the data bounds, then azimuth, elevation, zoom."""

    azimuth: float = 0.0
    elevation: float = 0.0
    zoom: float = 1.0
    parallel: bool = False

    def __post_init__(self) -> None:
        for name in ("azimuth", "elevation", "zoom"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float) or not is_finite(value):
                raise VolrenError(f"camera {name} must be a finite number, got {value!r:.40}")
        if not isinstance(self.parallel, bool):
            raise VolrenError(f"camera parallel must be true or false, got {self.parallel!r}")
        check_zoom(self.zoom, self.parallel)

    def camera(self, bounds: Sequence[float], aspect: float = 1.0) -> Camera:
        return Camera.orbit(bounds, self.azimuth, self.elevation, self.zoom, self.parallel, aspect)

    def to_dict(self) -> dict[str, Any]:
        return {
            "azimuth": self.azimuth,
            "elevation": self.elevation,
            "zoom": self.zoom,
            "parallel": self.parallel,
        }


def camera_from_dict(data: Mapping[str, Any]) -> OrbitView | Camera:
    """An explicit camera when the dict has a 'position', else an orbit description."""
    if not isinstance(data, Mapping):
        raise VolrenError(f"'camera' must be a JSON object, got {type(data).__name__}")
    if "position" in data:
        return Camera.from_dict(dict(data))
    unknown = set(data) - {"azimuth", "elevation", "zoom", "parallel"}
    if unknown:
        raise VolrenError(f"unknown camera keys {sorted(unknown)}; use azimuth, elevation, zoom, parallel")
    return OrbitView(**data)


def scene_transfer_function(
    data: Mapping[str, Any],
) -> TransferFunction | LabelTransferFunction | ChannelTransferFunction:
    """A scene's inline TF: 1D or 2D (`transfer_function_from_dict`), a TF per label, or a TF per channel."""
    if isinstance(data, Mapping) and data.get("kind") == "labels":
        return LabelTransferFunction.from_dict(data)
    if isinstance(data, Mapping) and data.get("kind") == "channels":
        return ChannelTransferFunction.from_dict(data)
    return transfer_function_from_dict(data)


def channel_pick(value: Any, what: str = "scene 'volume.channels'") -> bool | tuple[int, ...] | None:
    """A scene's channel pick: None (none), true (every channel) or a list of channel numbers."""
    if value is None or value is False or value is True:
        return value or None
    if not isinstance(value, list | tuple) or not value or len(value) > MAX_CHANNELS:
        raise VolrenError(
            f"{what} must be true or a list of 1 to {MAX_CHANNELS} channel numbers, got {value!r:.60}"
        )
    if not all(isinstance(c, int) and not isinstance(c, bool) and c >= 0 for c in value) or len(
        set(value)
    ) != len(value):
        raise VolrenError(f"{what} must list different whole numbers >= 0, got {list(value)!r:.60}")
    return tuple(value)


@dataclass(frozen=True)
class Scene:
    """Everything `volren render` needs; `volume` is filled in by the loader, not serialized."""

    volume_path: str | None
    #: TransferFunction1D or TransferFunction2D; a LabelTransferFunction for a volume with labels;
    #: a ChannelTransferFunction for a volume with channels
    transfer_function: TransferFunction | LabelTransferFunction | ChannelTransferFunction
    camera: OrbitView | Camera = OrbitView()
    settings: RenderSettings = RenderSettings()
    scalars: str | None = None
    renderer: str = "auto"  #: a registered name, or "auto" (`volren.quality.choose_renderer`)
    size: tuple[int, int] = (512, 512)
    volume: Volume | None = None
    extra: Mapping[str, Any] = field(default_factory=dict)
    #: the label volume's file (a segmentation on the volume's grid, `volren.io.label_io`), or None
    labels_path: str | None = None
    #: the channels read from the volume's file (`volren.io.channel_io`): True (all), the file's
    #: channel numbers, or None (one field)
    channels: bool | tuple[int, ...] | None = None

    def __post_init__(self) -> None:
        w, h = self.size
        if not all(isinstance(v, int) and not isinstance(v, bool) and v > 0 for v in (w, h)):
            raise VolrenError(f"scene size must be two positive integers, got {self.size!r}")
        object.__setattr__(self, "size", (w, h))

    def resolved_camera(self, bounds: Sequence[float] | None = None) -> Camera:
        """The camera to render with; an orbit view needs the volume's bounds."""
        if isinstance(self.camera, Camera):
            return self.camera
        if bounds is None:
            if self.volume is None:
                raise VolrenError("the scene has no volume to place the camera on")
            bounds = self.volume.bounds
        w, h = self.size
        return self.camera.camera(bounds, w / h)

    def with_volume(self, volume: Volume) -> Scene:
        return replace(self, volume=volume)

    def to_dict(self) -> dict[str, Any]:
        data: dict[str, Any] = dict(self.extra)
        volume: dict[str, Any] = {"path": self.volume_path, "scalars": self.scalars}
        if self.labels_path is not None:
            volume["labels"] = self.labels_path
        if self.channels is not None:
            volume["channels"] = True if self.channels is True else list(self.channels or ())
        data.update(
            {
                "version": SCENE_FORMAT_VERSION,
                "volume": volume,
                "transfer_function": self.transfer_function.to_dict(),
                "camera": self.camera.to_dict(),
                "settings": self.settings.to_dict(),
                "renderer": self.renderer,
                "size": list(self.size),
            }
        )
        return data

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Scene:
        """Build from scene JSON whose 'transfer_function' is already an inline dict."""
        check_format_version(data, "scene", SCENE_FORMAT_VERSION)
        volume = data.get("volume") or {}
        if not isinstance(volume, Mapping):
            raise VolrenError(
                "scene 'volume' must be an object with 'path' and optional 'scalars', 'labels' and 'channels'"
            )
        for key in ("path", "scalars", "labels"):
            if volume.get(key) is not None and not isinstance(volume.get(key), str):
                raise VolrenError(f"scene 'volume.{key}' must be a string, got {volume.get(key)!r}")
        if "transfer_function" not in data:
            if data.get("kind") in ("1d", "2d") or "opacity" in data or "widgets" in data:
                raise VolrenError(
                    "this is a transfer function, not a scene: give it with --tf (and the volume as INPUT)"
                )
            raise VolrenError("scene has no 'transfer_function'")
        size = data.get("size", [512, 512])
        if not isinstance(size, Sequence) or isinstance(size, str) or len(size) != 2:
            raise VolrenError(f"scene 'size' must be [width, height], got {size!r}")
        known = {"version", "volume", "transfer_function", "camera", "settings", "renderer", "size"}
        return cls(
            volume_path=volume.get("path"),
            scalars=volume.get("scalars"),
            transfer_function=scene_transfer_function(data["transfer_function"]),
            camera=camera_from_dict(data.get("camera", {})),
            settings=RenderSettings.from_dict(data.get("settings", {})),
            renderer=str(data.get("renderer", "auto")),
            size=(size[0], size[1]),
            extra={k: v for k, v in data.items() if k not in known},
            labels_path=volume.get("labels"),
            channels=channel_pick(volume.get("channels")),
        )
