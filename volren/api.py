"""`volren.render`: one call from a volume (or a file, or a PyVista dataset) to an RGBA image;
`volren.drawing`: the same, ready to draw many frames with one prepared renderer."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from os import PathLike, fspath
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
from volren.model.channels import ChannelTransferFunction
from volren.model.clip_region import ClipRegion, check_box
from volren.model.default_tf import default_transfer_function
from volren.model.labels import LabelTransferFunction
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


def as_transfer_function(
    tf: Any, volume: Volume
) -> TransferFunction | LabelTransferFunction | ChannelTransferFunction:
    """A TF (1D or 2D, a TF per label, or a TF per channel) from a TF, a path, a TF JSON dict, or
    None (the default for this volume: 1D, or for a volume with channels a TF per channel,
    `volren.io.channel_io.default_channel_tf`)."""
    if tf is None:
        channels = getattr(volume, "channels", None)
        if channels is not None:
            from volren.io.channel_io import default_channel_tf

            return default_channel_tf(channels)
        return default_transfer_function(volume)
    if isinstance(
        tf, TransferFunction1D | TransferFunction2D | LabelTransferFunction | ChannelTransferFunction
    ):
        return tf
    if isinstance(tf, Mapping):
        if tf.get("kind") == "labels":
            return LabelTransferFunction.from_dict(tf)
        if tf.get("kind") == "channels":
            return ChannelTransferFunction.from_dict(tf)
        return transfer_function_from_dict(tf)
    if isinstance(tf, str | PathLike):
        from volren.io.tf_io import load_any_transfer_function

        return load_any_transfer_function(fspath(tf))
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
    labels: Any = None,
    label_tfs: Mapping[int, Any] | None = None,
    hidden_labels: Sequence[int] = (),
    label_info: Any = None,
    channels: bool | Sequence[int] | None = None,
    channel_tfs: Mapping[int, Any] | None = None,
    channel_weights: Mapping[int, float] | None = None,
    hidden_channels: Sequence[int] = (),
    **settings: Any,
) -> Drawing:
    """What `render` draws, ready for many frames: the input read, `auto` and the quality resolved
    (for the camera given), the scene checked; the arguments are `render`'s. In a ``with`` block
    the renderer is prepared once, on the first frame, and kept: ``d.frame(d.orbit(azimuth=a))``
    draws another view and ``d.set_transfer_function(tf)`` another TF without preparing the
    volume again (`volren.draw.Drawing`)."""
    from volren.draw.channels import wants_channels
    from volren.draw.labelled import labelled, wants_labels

    if clip_planes or crop is not None:
        settings["clip"] = ClipRegion(tuple(clip_planes), None if crop is None else check_box(crop), clip_cap)
    elif clip_cap:
        raise VolrenError("clip_cap: give clip_planes or crop (there is nothing cut to cap)")
    source = _open_input(volume, scalars, memory, level, channels)
    vol = source.stand_in()
    transfer = as_transfer_function(tf, vol)
    width, height = parse_size(size)
    for name, value in (("azimuth", azimuth), ("elevation", elevation), ("zoom", zoom)):
        if not is_finite(value):
            raise VolrenError(f"{name} must be finite, got {value!r:.40}")
    on_cluster = cluster is not None or scheduler is not None  # an empty one is refused, not ignored
    if wants_labels(vol, transfer, labels, label_info, label_tfs, hidden_labels):
        if on_cluster:
            raise VolrenError("labels: label volumes are drawn from a volume read whole, not on a cluster")
        if source.bricks:  # an OME-Zarr image: its label images lie on its full resolution (NGFF)
            vol = _whole_image(volume, level, memory)
            transfer = as_transfer_function(tf, vol)  # a default one from the whole image's values
        if wants_channels(vol, transfer, channels, channel_tfs, channel_weights, hidden_channels):
            raise VolrenError(
                "channels: a volume is drawn with labels or with channels, not both at once yet"
            )
        vol, transfer = labelled(vol, transfer, labels, label_info, label_tfs, hidden_labels)  # type: ignore[arg-type]
        source = VolumeInput(vol)
    elif wants_channels(vol, transfer, channels, channel_tfs, channel_weights, hidden_channels):
        vol, transfer = _with_channels(
            vol, tf, transfer, channel_tfs, channel_weights, hidden_channels, on_cluster
        )
        source = VolumeInput(vol)
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
    labels: Any = None,
    label_tfs: Mapping[int, Any] | None = None,
    hidden_labels: Sequence[int] = (),
    label_info: Any = None,
    channels: bool | Sequence[int] | None = None,
    channel_tfs: Mapping[int, Any] | None = None,
    channel_weights: Mapping[int, float] | None = None,
    hidden_channels: Sequence[int] = (),
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

    A segmented volume (Real-Time Volume Graphics, chapter 16: a TF per label) draws with `labels`:
    a segmentation file on the volume's grid (NIfTI, NRRD or 3D Slicer's .seg.nrrd, MetaImage,
    .vti, ...: `volren.io.label_io.load_labels`), an array indexed [k, j, i] as the volume's values,
    or a `LabelMap`; or with a volume that has labels already. Each label draws with `tf` recoloured
    (label 0 as it is), unless `tf` is a `LabelTransferFunction`; `label_info` (a label-info JSON
    file or dict: names, colours, opacities, TFs), `label_tfs` ({label: a 1D TF or TF file}) and
    `hidden_labels` (labels not drawn) change that, in this order (`volren.draw.labelled`). `auto`
    then picks among the renderers that draw labels.

    A multi-channel volume (Max 1995, section 2: the channels' extinctions and emissions add, a TF
    each) draws with `channels`: True for every component of a vector array (or every channel of an
    OME-Zarr image's c axis, with its ``omero`` colours, windows, labels and active flags), or a
    list of the file's channel numbers; or with a `UniformVolume` that has `channels`. Each channel
    draws with its default ramp (`volren.io.channel_io.default_channel_tf`), unless `tf` is a
    `ChannelTransferFunction` (or its file), or a 1D TF for every channel; `channel_tfs`
    ({channel: a 1D TF or TF file}), `channel_weights` ({channel: weight >= 0}) and
    `hidden_channels` change that, in this order (`volren.draw.channels`). Channels are the file's
    numbers. `auto` then picks among the renderers that mix channels, with pre-integration off.
    """
    ready = drawing(volume, tf, renderer, size, azimuth, elevation, zoom, parallel, camera, scalars, quality, memory,
                    level, cluster, scheduler, clip_planes, crop, clip_cap, labels=labels, label_tfs=label_tfs,
                    hidden_labels=hidden_labels, label_info=label_info, channels=channels, channel_tfs=channel_tfs,
                    channel_weights=channel_weights, hidden_channels=hidden_channels, **settings)  # fmt: skip
    return ready.frame(progress=progress).image


def _open_input(volume: Any, scalars: str | None, memory: int | str | None, level: int | None,
                channels: Any = None) -> DrawInput:  # fmt: skip
    """What `volume` names, to draw from: an OME-Zarr image (within `memory`, at `level`), or a
    volume (`as_volume`); `memory` and `level` are refused for anything but an OME-Zarr image.
    `channels` (True or channel numbers): the channels read too, the volume read whole."""
    from volren.io.channel_io import wants_pick
    from volren.io.ome_zarr_io import parse_memory

    if not is_ome_zarr_path(volume):
        if memory is not None or level is not None:
            raise VolrenError("memory and level apply to an OME-Zarr image (a .zarr folder or URL)")
        if wants_pick(channels):
            return VolumeInput(_channel_volume(volume, scalars, channels))
        return VolumeInput(as_volume(volume, scalars))
    budget = parse_memory(memory) if isinstance(memory, str) else memory
    if budget is not None and (isinstance(budget, bool) or budget < 1):
        raise VolrenError(f"memory must be a positive number of bytes or a size like 2GB, got {memory!r}")
    if wants_pick(channels):
        from volren.io.volume_io import load_ome_zarr

        return VolumeInput(_named_channels(lambda: load_ome_zarr(volume, level, budget, channels)))
    return open_ome_zarr(volume, budget, level)


def _whole_image(volume: Any, level: int | None, memory: int | str | None) -> Any:
    """An OME-Zarr image read whole at full resolution (within `memory`), to draw with labels."""
    from volren.io.ome_zarr_io import parse_memory
    from volren.io.volume_io import load_ome_zarr

    if level not in (None, 0):
        raise VolrenError(
            f"labels: label images lie on the image's full resolution; level {level} does not apply"
        )
    budget = parse_memory(memory) if isinstance(memory, str) else memory
    try:
        return load_ome_zarr(volume, 0, budget)
    except VolrenError as exc:
        raise VolrenError(f"labels: {exc}") from None


def _named_channels(load: Any) -> Any:
    """`load()`, its one-line errors starting with the argument's name, `channels`."""
    try:
        return load()
    except VolrenError as exc:
        raise VolrenError(f"channels: {exc}") from None


def _channel_volume(volume: Any, scalars: str | None, channels: Any) -> Volume:
    """A volume with channels: a file or PyVista dataset read with them, or a volume in memory
    with channels, `channels` picking among them."""
    from volren import io
    from volren.draw.channels import picked_volume

    if isinstance(volume, UniformVolume | TetVolume):
        if not isinstance(volume, UniformVolume) or volume.channels is None:
            raise VolrenError(f"channels: {volume.name} has one field; give a UniformVolume with channels (a "
                              "ChannelSet), or a file or dataset whose array has several components")  # fmt: skip
        return picked_volume(volume, channels, "channels")
    if isinstance(volume, str | PathLike):
        return _named_channels(lambda: io.load_volume(fspath(volume), scalars=scalars, channels=channels))
    return _named_channels(lambda: io.from_pyvista(volume, scalars=scalars, channels=channels))


def _with_channels(vol: Volume, tf: Any, transfer: Any, tfs: Any, weights: Any, hidden: Any,
                   on_cluster: bool) -> tuple[UniformVolume, ChannelTransferFunction]:  # fmt: skip
    """The volume and its TF per channel (`volren.draw.channels.channelled`): `tf` None gives the
    channels' default look, a 1D TF is every channel's."""
    from volren.draw.channels import channelled

    if on_cluster:
        raise VolrenError(
            "channels: multi-channel volumes are drawn from a volume read whole, not on a cluster"
        )
    given = transfer if tf is not None or isinstance(transfer, ChannelTransferFunction) else None
    if given is not None and not isinstance(given, TransferFunction1D | ChannelTransferFunction):
        raise VolrenError("channels: channels draw with a 1D transfer function each; got a 2D one")
    return channelled(vol, given, tfs, weights, hidden)
