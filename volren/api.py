"""`volren.render`: one call from a volume (or a file, or a PyVista dataset) to an RGBA image;
`volren.drawing`: the same, ready to draw many frames with one prepared renderer."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from os import PathLike
from typing import Any

import numpy as np
from numpy.typing import NDArray

from volren.draw import (
    Drawing,
    DrawInput,
    VolumeInput,
    check_scene,
    is_ome_zarr_path,
    open_ome_zarr,
    prepared_renderer,
    resolve_scene,
)
from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.clip_region import ClipRegion, check_box
from volren.model.default_tf import default_transfer_function
from volren.model.scene import Scene
from volren.model.settings import RenderSettings, is_finite
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import (
    TransferFunction,
    TransferFunction2D,
    transfer_function_from_dict,
)
from volren.model.volume import TetVolume, UniformVolume, Volume
from volren.renderers.base import ProgressCallback

__all__ = [
    "as_transfer_function",
    "as_volume",
    "check_scene",
    "drawing",
    "parse_size",
    "prepared_renderer",
    "render",
]


def as_volume(volume: Any, scalars: str | None = None) -> Volume:
    """A model volume from a model volume, a path, or a PyVista dataset."""
    if isinstance(volume, UniformVolume | TetVolume):
        return volume
    from volren import io

    if isinstance(volume, str | PathLike):
        return io.load_volume(volume, scalars=scalars)
    return io.from_pyvista(volume, scalars=scalars)


def as_transfer_function(tf: Any, volume: Volume) -> TransferFunction:
    """A TF (1D or 2D) from a TF, a path, a TF JSON dict, or None (the default, 1D, for this volume)."""
    if tf is None:
        return default_transfer_function(volume)
    if isinstance(tf, TransferFunction1D | TransferFunction2D):
        return tf
    if isinstance(tf, Mapping):
        return transfer_function_from_dict(tf)
    if isinstance(tf, str | PathLike):
        from volren import io

        return io.load_transfer_function(tf)
    raise VolrenError(f"cannot use a {type(tf).__name__} as a transfer function")


def parse_size(size: Any) -> tuple[int, int]:
    """(w, h) from an int, a (w, h) pair or 'W' / 'WxH' text."""
    if isinstance(size, str):
        parts = size.lower().split("x")
        try:
            values = [int(p) for p in parts]
        except ValueError:
            raise VolrenError(f"image size must look like 512 or 640x480, got {size!r}") from None
    elif isinstance(size, int):
        values = [size]
    else:
        values = list(size)
    if len(values) == 1:
        values = values * 2
    if len(values) != 2 or not all(isinstance(v, int | np.integer) and v > 0 for v in values):
        raise VolrenError(f"image size must be one or two positive integers, got {size!r}")
    return int(values[0]), int(values[1])


def drawing(
    volume: Any,
    tf: Any = None,
    renderer: str = "auto",
    size: Any = (512, 512),
    azimuth: float = 0.0,
    elevation: float = 0.0,
    zoom: float = 1.0,
    parallel: bool = False,
    camera: Camera | None = None,
    scalars: str | None = None,
    quality: str = "default",
    memory: int | str | None = None,
    level: int | None = None,
    cluster: str | None = None,
    scheduler: str | None = None,
    clip_planes: Sequence[Any] = (),
    crop: Sequence[float] | None = None,
    clip_cap: bool = False,
    **settings: Any,
) -> Drawing:
    """What `render` draws, ready for many frames: the input read, `auto` and the quality resolved
    (for the camera given), the scene checked; the arguments are `render`'s. In a ``with`` block
    the renderer is prepared once, on the first frame, and kept: ``d.frame(d.orbit(azimuth=a))``
    draws another view and ``d.set_transfer_function(tf)`` another TF without preparing the
    volume again (`volren.draw.Drawing`)."""
    if clip_planes or crop is not None:
        settings["clip"] = ClipRegion(tuple(clip_planes), None if crop is None else check_box(crop), clip_cap)
    elif clip_cap:
        raise VolrenError("clip_cap: give clip_planes or crop (there is nothing cut to cap)")
    source = _open_input(volume, scalars, memory, level)
    vol = source.stand_in()
    transfer = as_transfer_function(tf, vol)
    width, height = parse_size(size)
    for name, value in (("azimuth", azimuth), ("elevation", elevation), ("zoom", zoom)):
        if not is_finite(value):
            raise VolrenError(f"{name} must be finite, got {value!r:.40}")
    on_cluster = cluster is not None or scheduler is not None  # an empty one is refused, not ignored
    cam = camera or Camera.orbit(source.bounds, azimuth, elevation, zoom, parallel, width / height)
    # the level's settings on the defaults, then the caller's fields again on top (they win; options merge)
    scene = Scene(None, transfer, cam, RenderSettings().with_(**settings), renderer=renderer, size=(width, height),
                  volume=vol)  # fmt: skip
    scene, _ = resolve_scene(scene, source, quality, cameras=(cam,), on_cluster=on_cluster)
    scene = replace(
        scene, settings=scene.settings.with_(**{k: v for k, v in settings.items() if k != "options"})
    )
    result = Drawing(source, scene, quality, cluster, scheduler)
    result.check(tf_name=str(tf) if isinstance(tf, str | PathLike) else None)
    return result


def render(
    volume: Any,
    tf: Any = None,
    renderer: str = "auto",
    size: Any = (512, 512),
    azimuth: float = 0.0,
    elevation: float = 0.0,
    zoom: float = 1.0,
    parallel: bool = False,
    camera: Camera | None = None,
    scalars: str | None = None,
    progress: ProgressCallback | None = None,
    quality: str = "default",
    memory: int | str | None = None,
    level: int | None = None,
    cluster: str | None = None,
    scheduler: str | None = None,
    clip_planes: Sequence[Any] = (),
    crop: Sequence[float] | None = None,
    clip_cap: bool = False,
    **settings: Any,
) -> NDArray[np.float32]:
    """Render offscreen; returns float32 (H, W, 4) premultiplied RGBA over black, row 0 on top.

    `volume` may be a UniformVolume/TetVolume, a file path or a PyVista dataset; `tf` a
    TransferFunction1D or TransferFunction2D, a TF JSON path or dict, or None for a default. The
    camera is DESIGN.md's orbit (reset on the bounds, then azimuth, elevation, zoom) unless
    `camera` is given. `renderer` "auto" is the fastest measured renderer that draws the scene at
    `quality` (`volren.quality`: draft, interactive, default, high, exact), whose measured settings
    apply; other keyword arguments are RenderSettings fields (step, preintegration, shade,
    blend_mode, options, ...) and win over the level's.

    `clip_planes` ((origin, normal) pairs in world units, at most six) keep the side each normal
    points to, and `crop` (xmin, xmax, ymin, ymax, zmin, zmax) the inside of a box: rays are cut
    to the kept region exactly (`RenderSettings.clip`), and `auto` picks a renderer that clips;
    `clip_cap=True` draws the cut faces opaque in the TF's colour there (`ClipRegion.cap`).

    An OME-Zarr path draws as `volren render` does (`volren.draw.ZarrImageInput`): the `level`
    given, else the full resolution (the level the view needs at quality draft and interactive),
    read whole within `memory` (bytes or "2GB"; default 8 GB) or streamed brick by brick. `cluster` ("local" or "local:N") or `scheduler` (an address) draws
    the bricks on a dask.distributed cluster (`volren.bricked.cluster`).
    """
    ready = drawing(volume, tf, renderer, size, azimuth, elevation, zoom, parallel, camera, scalars, quality, memory,
                    level, cluster, scheduler, clip_planes, crop, clip_cap, **settings)  # fmt: skip
    return ready.frame(progress=progress).image


def _open_input(volume: Any, scalars: str | None, memory: int | str | None, level: int | None) -> DrawInput:
    """What `volume` names, to draw from: an OME-Zarr image (within `memory`, at `level`), or a
    volume (`as_volume`); `memory` and `level` are refused for anything but an OME-Zarr image."""
    from volren.io.ome_zarr_io import parse_memory

    if not is_ome_zarr_path(volume):
        if memory is not None or level is not None:
            raise VolrenError("memory and level apply to an OME-Zarr image (a .zarr folder or URL)")
        return VolumeInput(as_volume(volume, scalars))
    budget = parse_memory(memory) if isinstance(memory, str) else memory
    if budget is not None and (isinstance(budget, bool) or budget < 1):
        raise VolrenError(f"memory must be a positive number of bytes or a size like 2GB, got {memory!r}")
    return open_ome_zarr(volume, budget, level)
