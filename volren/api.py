"""`volren.render`: one call from a volume (or a file, or a PyVista dataset) to an RGBA image."""

from __future__ import annotations

import warnings
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from os import PathLike
from typing import Any

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError, VolrenWarning
from volren.model.camera import Camera
from volren.model.default_tf import default_transfer_function
from volren.model.settings import RenderSettings, check_step, is_finite
from volren.model.tf_coverage import coverage_problem
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import (
    TransferFunction,
    TransferFunction2D,
    transfer_function_from_dict,
)
from volren.model.volume import TetVolume, UniformVolume, Volume
from volren.renderers.base import ProgressCallback, Renderer, render_frame


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


def check_scene(
    volume: Volume,
    tf: TransferFunction,
    settings: RenderSettings,
    tf_name: str | None = None,
    step_name: str = "render setting step",
) -> None:
    """What `volren render` and `volren.render` check before drawing, so that bad input is an error
    or a warning instead of a black image and success: a step too small to honour (an error naming
    it as `step_name`), and a TF that shows nothing of the data (a VolrenWarning naming `tf_name`,
    the TF file, where there is one)."""
    check_step(settings.step, volume.bounds, volume.characteristic_length, step_name)
    problem = coverage_problem(tf, volume.value_range)
    if problem:
        warnings.warn(f"{tf_name or 'transfer function'}: {problem}", VolrenWarning, stacklevel=2)


@contextmanager
def prepared_renderer(
    name: str, volume: Volume, tf: TransferFunction, settings: RenderSettings | None = None
) -> Iterator[Renderer]:
    """``with prepared_renderer(...) as r``: a new renderer `name` holding the volume, TF and
    settings, released at the end of the block (the Protocol asks for no context-manager methods).
    A step too small for any renderer to honour is refused here, where the bench and the reference
    images pass as well as `render`."""
    from volren.renderers.registry import registry

    settings = settings or RenderSettings()
    check_step(settings.step, volume.bounds, volume.characteristic_length)
    renderer = registry.create(name)
    try:
        renderer.set_volume(volume)
        renderer.set_transfer_function(tf)
        renderer.set_settings(settings)
        yield renderer
    finally:
        renderer.release()


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

    An OME-Zarr path draws as `volren render` does (`volren.bricked.zarr_input`): the `level`
    given, else the full resolution (the level the view needs at quality draft and interactive),
    read whole within `memory` (bytes or "2GB"; default 8 GB) or streamed brick by brick. `cluster` ("local" or "local:N") or `scheduler` (an address) draws
    the bricks on a dask.distributed cluster (`volren.bricked.cluster`).
    """
    zarr_input = _zarr_input(volume, memory, level)
    vol = zarr_input.stand_in() if zarr_input is not None else as_volume(volume, scalars)
    transfer = as_transfer_function(tf, vol)
    width, height = parse_size(size)
    for name, value in (("azimuth", azimuth), ("elevation", elevation), ("zoom", zoom)):
        if not is_finite(value):
            raise VolrenError(f"{name} must be finite, got {value!r:.40}")
    from volren.model.scene_class import SceneClass
    from volren.quality import resolve

    on_cluster = cluster is not None or scheduler is not None  # an empty one is refused, not ignored
    bounds = zarr_input.bounds if zarr_input is not None else vol.bounds
    cam = camera or Camera.orbit(bounds, azimuth, elevation, zoom, parallel, width / height)
    # the level's settings on the defaults, then the caller's fields again on top (they win; options merge)
    renderer, at_level, _ = resolve(SceneClass.of(vol, transfer), transfer.dims, renderer, quality, RenderSettings().with_(**settings),
                                    bricks=zarr_input is not None or on_cluster, cameras=(cam,), bounds=bounds)  # fmt: skip
    render_settings = at_level.with_(**{k: v for k, v in settings.items() if k != "options"})
    check_scene(vol, transfer, render_settings, tf_name=str(tf) if isinstance(tf, str | PathLike) else None)
    if on_cluster:
        from volren.bricked.cluster import render_on_cluster

        image, _, _ = render_on_cluster(cluster, scheduler, zarr_input or vol, renderer, render_settings, transfer,
                                        cam, width, height, level, progress, quality)  # fmt: skip
        return image
    source = None
    if zarr_input is not None:
        frame = zarr_input.frame(renderer, cam, width, height, level, quality)
        vol, source = frame.volume or vol, frame.source
    with prepared_renderer(renderer, vol, transfer, render_settings) as r:
        if source is not None:
            from volren.bricked.sort_last import render_streamed

            image, _ = render_streamed(r, source, transfer, cam, width, height, progress)
        else:
            image, _ = render_frame(r, cam, width, height, progress, label=renderer)
        return image


def _zarr_input(volume: Any, memory: int | str | None, level: int | None) -> Any:
    """The opened OME-Zarr image when `volume` is a path to one (None otherwise); `memory` and
    `level` are refused for anything else."""
    from volren.io.ome_zarr_io import is_ome_zarr, parse_memory

    if not (isinstance(volume, str | PathLike) and is_ome_zarr(volume)):
        if memory is not None or level is not None:
            raise VolrenError("memory and level apply to an OME-Zarr image (a .zarr folder or URL)")
        return None
    from volren.bricked.zarr_input import ZarrInput

    budget = parse_memory(memory) if isinstance(memory, str) else memory
    if budget is not None and (isinstance(budget, bool) or budget < 1):
        raise VolrenError(f"memory must be a positive number of bytes or a size like 2GB, got {memory!r}")
    zarr_input = ZarrInput(volume, budget)
    if level is not None:
        zarr_input.check_level(level)
    return zarr_input
