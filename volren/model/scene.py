"""A scene: what to render (volume, transfer function), from where (camera) and how (settings).

Scene files are versioned JSON (see `Scene.to_dict`); the volume is referenced by path, the
transfer function is stored inline. Reading and writing files is `volren.io.scene_io`'s job.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

from volren.errors import VolrenError
from volren.model.camera import Camera, check_zoom
from volren.model.file_version import check_format_version
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


@dataclass(frozen=True)
class Scene:
    """Everything `volren render` needs; `volume` is filled in by the loader, not serialized."""

    volume_path: str | None
    transfer_function: TransferFunction  # TransferFunction1D or TransferFunction2D
    camera: OrbitView | Camera = OrbitView()
    settings: RenderSettings = RenderSettings()
    scalars: str | None = None
    renderer: str = "auto"  #: a registered name, or "auto" (`volren.quality.choose_renderer`)
    size: tuple[int, int] = (512, 512)
    volume: Volume | None = None
    extra: Mapping[str, Any] = field(default_factory=dict)

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
        data.update(
            {
                "version": SCENE_FORMAT_VERSION,
                "volume": {"path": self.volume_path, "scalars": self.scalars},
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
            raise VolrenError("scene 'volume' must be an object with 'path' and optional 'scalars'")
        for key in ("path", "scalars"):
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
            transfer_function=transfer_function_from_dict(data["transfer_function"]),
            camera=camera_from_dict(data.get("camera", {})),
            settings=RenderSettings.from_dict(data.get("settings", {})),
            renderer=str(data.get("renderer", "auto")),
            size=(size[0], size[1]),
            extra={k: v for k, v in data.items() if k not in known},
        )
