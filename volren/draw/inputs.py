"""What a frame is drawn from: a volume in memory (a file read whole, one step of a time series),
or an OME-Zarr image whose level is chosen frame by frame and read whole or streamed brick by
brick (`volren.bricked.zarr_input`).

Why one abstraction: `volren.render`, `volren render`, `volren movie` and the app drew both kinds,
and each asked "is this an OME-Zarr image?" itself. A `DrawInput` answers the questions every
caller had: the volume to set the scene up on (`stand_in`), the bounds to place the camera on,
whether `auto` must choose a renderer that draws bricks, and what one frame draws (`frame`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from os import PathLike, fspath
from typing import TYPE_CHECKING, Any, Protocol, cast

from volren.model.camera import Camera
from volren.model.volume import Volume
from volren.quality import DEFAULT_LEVEL

if TYPE_CHECKING:
    from volren.bricked.source import BrickSource
    from volren.bricked.zarr_input import ZarrInput


@dataclass(frozen=True)
class FrameData:
    """What one frame draws: a volume read whole, or a source streamed brick by brick; `note` says
    which level of an image it is, for the line a command prints (empty for a plain volume)."""

    volume: Volume | None = None
    source: BrickSource | None = None
    note: str = ""


class DrawInput(Protocol):
    """Something a frame is drawn from (`VolumeInput`, `ZarrImageInput`)."""

    #: Whether only renderers that draw bricks apply (`volren.quality.resolve`'s `bricks`).
    bricks: bool

    @property
    def bounds(self) -> Sequence[float]:
        """Where the camera is placed: the same for every frame, whatever level is drawn."""
        ...

    def stand_in(self) -> Volume:
        """The volume the scene is set up on (default TF, checks, `auto`'s choice)."""
        ...

    def frame(self, renderer: str, camera: Camera, width: int, height: int,
              quality: str = DEFAULT_LEVEL) -> FrameData:  # fmt: skip
        """What `renderer` draws for `camera` at `width` x `height` at `quality`."""
        ...

    def on_cluster(self) -> tuple[Any, int | None]:
        """What a cluster draws (`volren.draw.frame.draw_on_cluster`): a volume or an opened image,
        and the level asked for (None: the level the quality draws)."""
        ...


class VolumeInput:
    """A volume in memory: a file read whole, a PyVista dataset, one step of a time series."""

    bricks = False

    def __init__(self, volume: Volume) -> None:
        self.volume = volume

    @property
    def bounds(self) -> Sequence[float]:
        return self.volume.bounds

    def stand_in(self) -> Volume:
        return self.volume

    def frame(self, renderer: str, camera: Camera, width: int, height: int,
              quality: str = DEFAULT_LEVEL) -> FrameData:  # fmt: skip
        return FrameData(volume=self.volume)

    def on_cluster(self) -> tuple[Any, int | None]:
        return self.volume, None


class ZarrImageInput:
    """An opened OME-Zarr image (`ZarrInput`) and the level asked for (None: the level each frame's
    view and quality need, `ZarrInput.frame`). The scene is set up on its coarsest level, read
    once; the camera on its full resolution's bounds."""

    bricks = True

    def __init__(self, image: ZarrInput, level: int | None = None) -> None:
        if level is not None:
            image.check_level(level)
        self.image = image
        self.level = level
        self._stand_in: Volume | None = None

    @property
    def bounds(self) -> Sequence[float]:
        return self.image.bounds

    def stand_in(self) -> Volume:
        if self._stand_in is None:
            self._stand_in = self.image.stand_in()
        return self._stand_in

    def frame(self, renderer: str, camera: Camera, width: int, height: int,
              quality: str = DEFAULT_LEVEL) -> FrameData:  # fmt: skip
        frame = self.image.frame(renderer, camera, width, height, self.level, quality)
        source = cast("BrickSource | None", frame.source)
        return FrameData(frame.volume, source, f" ({self.image.name} {frame.describe()})")

    def on_cluster(self) -> tuple[Any, int | None]:
        return self.image, self.level


def is_ome_zarr_path(data: Any) -> bool:
    """Whether `data` is a path or URL of an OME-Zarr image."""
    from volren.io.ome_zarr_io import is_ome_zarr

    return isinstance(data, str | PathLike) and is_ome_zarr(fspath(data))


def open_ome_zarr(path: str | PathLike, memory: int | None = None, level: int | None = None,
                  memory_name: str = "memory") -> ZarrImageInput:  # fmt: skip
    """The OME-Zarr image at `path`, to be drawn within `memory` bytes (None: 8 GiB; `memory_name`
    is how the caller names it in errors) at `level` (None: each frame's)."""
    from volren.bricked.zarr_input import ZarrInput

    return ZarrImageInput(ZarrInput(fspath(path), memory, memory_name), level)
