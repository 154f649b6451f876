"""`load_volume`: any supported file (or DICOM folder) to a model volume, or one clear error.

The steps, in order, each able to stop with a one-line VolrenError naming the file: the path
exists and is not empty; its format is known; its header is sane and fits in memory and its data
is as long as the header says (checked by volren, so no VTK reader sees a file that would crash
or hang it); the VTK reader runs with its messages caught (SLC and DICOM: volren's own reader
instead); what the reader returned is checked again; then the dataset becomes a model volume.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np
from numpy.typing import DTypeLike

from volren.errors import VolrenError, file_error
from volren.io import _pv, reader_messages
from volren.io.channel_io import ChannelPick, share_values, wants_pick
from volren.io.dataset import grid_from_view, tets_from_view, volume_from_grid
from volren.io.formats import SUPPORTED, find_format
from volren.io.formats.base import FileFormat, Grid, Inspection
from volren.io.formats.geometry import signed_as_declared
from volren.io.formats.raw import headerless_problem, load_raw
from volren.io.isolation import run_isolated
from volren.io.limits import check_layout
from volren.model.volume import TetVolume, UniformVolume

_RAW_DEFAULTS = {
    "dtype": None,
    "byte_order": "little",
    "spacing": (1.0, 1.0, 1.0),
    "origin": (0.0, 0.0, 0.0),
    "header_bytes": 0,
}


def _as_tuple(value: object) -> object:
    """A sequence as a tuple (to compare with a default), anything else as it is."""
    try:
        return tuple(value)  # type: ignore[call-overload]
    except TypeError:
        return value


def _existing(path: Path) -> None:
    if not path.exists():
        raise file_error(path, "no such file or folder")
    if path.is_file() and path.stat().st_size == 0:
        raise file_error(path, "empty file (0 bytes)")
    if not path.is_file() and not path.is_dir():
        raise file_error(path, "not a regular file or folder")


def load_ome_zarr(
    path: str | Path, level: int | None = None, memory: int | None = None, channels: ChannelPick = None
) -> UniformVolume:
    """An OME-Zarr image's level `level`, or (None) the finest that fits in `memory` bytes (default
    `ome_zarr_io.MAX_IN_MEMORY_BYTES`), with a one-line warning when that is not the finest. With
    `channels` (True or channel numbers), its c axis' channels (`ome_zarr_io.load_channels`)."""
    from volren.io import ome_zarr_io

    budget = memory if memory is not None else ome_zarr_io.MAX_IN_MEMORY_BYTES
    name = str(path).rstrip("/").rsplit("/", 1)[-1] if ome_zarr_io.is_url(path) else Path(path).name
    if wants_pick(channels):
        return ome_zarr_io.load_channels(path, channels, level, name=name, memory=budget)
    if level is None:
        level = ome_zarr_io.finest_level_said(ome_zarr_io.open_multiscale(path), budget, name)
    return ome_zarr_io.load_level(path, level, name=name, memory=budget)


def load_volume(
    path: str | Path,
    scalars: str | None = None,
    *,
    shape: Sequence[int] | None = None,
    dtype: DTypeLike | None = None,
    byte_order: str = "little",
    spacing: Sequence[float] = (1.0, 1.0, 1.0),
    origin: Sequence[float] = (0.0, 0.0, 0.0),
    header_bytes: int = 0,
    level: int | None = None,
    channels: ChannelPick = None,
) -> UniformVolume | TetVolume:
    """Load a volume file; the volume's `name` is the file name (the folder's, for DICOM).

    Formats: .vti, .vtk (legacy structured points or unstructured grid), .vtu, .nrrd/.nhdr,
    .mhd/.mha, .nii/.nii.gz, .slc, DICOM (a folder, or one .dcm file meaning its folder), and
    headerless raw data: any file when `shape` = (nx, ny, nz) is given, with `dtype`,
    `byte_order` ('little', 'big'), `spacing`, `origin` and `header_bytes` describing it.
    `scalars` names the array to render; None takes the active (else first) point array.

    An OME-Zarr image (a folder, or an fsspec URL ending in .zarr) gives its level `level`, or (None)
    its finest level that fits in memory (`load_ome_zarr`); `level` applies to nothing else.

    `channels` (True, or the component numbers to draw) reads a uniform grid's array of several
    components (or an OME-Zarr image's c axis) as a multi-channel volume (`volren.io.channel_io`):
    `values` is then the first channel picked, and the volume's `channels` all of them.

    Files with a header are read in a child process (`volren.io.isolation`): a reader that
    crashes on a corrupt file is a one-line error here, not the end of this process.
    """
    from volren.io.ome_zarr_io import is_ome_zarr

    if is_ome_zarr(path) and shape is None:
        if scalars is not None:
            raise file_error(
                path, f"an OME-Zarr image holds one field; there is no array {scalars!r} to choose"
            )
        return load_ome_zarr(path, level, channels=channels)
    if level is not None:
        raise file_error(path, f"level={level} applies to OME-Zarr images (a .zarr folder or URL) only")
    path = Path(path)
    _existing(path)
    if shape is not None:  # headerless raw: numpy reads it, nothing native to isolate
        if path.is_dir():
            raise file_error(path, "is a folder; headerless raw data (shape=...) must be a file")
        if wants_pick(channels):
            raise file_error(path, "headerless raw data holds one field; channels come from an array of several "
                                   "components")  # fmt: skip
        grid = load_raw(path, shape, dtype, byte_order, spacing, origin, header_bytes)
        return volume_from_grid(grid, path.name)
    given = {
        "dtype": dtype,
        "byte_order": byte_order,
        "spacing": _as_tuple(spacing),
        "origin": _as_tuple(origin),
        "header_bytes": header_bytes,
    }
    if given != _RAW_DEFAULTS:
        extra = ", ".join(f"{k}=" for k in given if given[k] != _RAW_DEFAULTS[k])
        raise file_error(path, f"{extra} describe headerless raw data only; give shape=(nx, ny, nz) too")
    if wants_pick(channels):
        return share_values(run_isolated(path, read_with_header, path, scalars, channels))
    return run_isolated(path, read_with_header, path, scalars)


def read_with_header(
    path: Path, scalars: str | None = None, channels: ChannelPick = None
) -> UniformVolume | TetVolume:
    """A file with a header (or a DICOM folder), read in this process: the child's side of
    `load_volume`."""
    fmt = find_format(path)
    if fmt is None:
        raise file_error(path, headerless_problem(path, flags=False))
    inspection = fmt.inspect(path)
    name = inspection.target.name  # a DICOM series is named after its folder
    if inspection.layout is not None:
        check_layout(path, inspection.layout)
    declared_spacing = inspection.facts.get("declared_spacing")
    own = fmt.read(path, inspection) if fmt.read is not None else None
    if own is not None:  # volren's own reader: no VTK reader sees the file
        if wants_pick(channels):
            raise file_error(path, f"{fmt.name} data holds one field here; channels come from an array of "
                                   "several components")  # fmt: skip
        if scalars is not None and scalars != fmt.array_name:
            raise file_error(path, f"no array named {scalars!r}; available: {fmt.array_name!r}")
        return volume_from_grid(signed_as_declared(own, declared_spacing), name)
    result = _pv.read(inspection.target, inspection.reader)
    problem = reader_messages.problem(result.log, inspection.target)
    if problem:
        raise file_error(path, problem)
    view = result.view
    if view is None:
        raise file_error(path, f"the VTK reader returned nothing (is it really {fmt.name}?)")
    view = fmt.check_output(path, view, result, inspection)
    source = str(path)
    if view.kind == "image":
        grid = _adjusted(fmt, grid_from_view(view, scalars, source, name, channels), result, inspection)
        return volume_from_grid(signed_as_declared(grid, declared_spacing), name)
    if wants_pick(channels):
        raise file_error(path, "channels are read from image data (a uniform grid), not from a mesh")
    if inspection.reader in ("vtu", "legacy-unstructured"):
        return tets_from_view(view, scalars, source, name)
    raise VolrenError(
        f"{path}: the reader returned {view.type_name}, which volren cannot render; volren reads {SUPPORTED}"
    )


def _adjusted(fmt: FileFormat, grid: Grid, result: _pv.ReadResult, inspection: Inspection) -> Grid:
    """`fmt.adjust` (a format's fixes of VTK's reading: value scaling, flips, byte swaps) on the
    grid, and on each of its channels alike."""
    if grid.channels is None:
        return fmt.adjust(grid, result, inspection)
    fixed = [fmt.adjust(replace(grid, values=channel, notes=[], info=[]), result, inspection)
             for channel in grid.channels]  # fmt: skip
    first = fixed[0]
    stacked = np.stack([g.values for g in fixed])
    return replace(first, values=stacked[0], channels=stacked, notes=grid.notes + first.notes,
                   info=grid.info + first.info)  # fmt: skip
