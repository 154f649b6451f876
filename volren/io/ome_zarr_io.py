"""OME-Zarr multiscale images (NGFF 0.4 on Zarr v2, written and read; NGFF 0.5 on Zarr v3, read):
the bricked, multiresolution format of volumes larger than memory.

Writing (`save_ome_zarr`): the pyramid of `volren.model.pyramid` (2x2x2 block means), each level
an array of bricks ("chunks"), voxel placement as NGFF's scale and translation per level (z, y, x
order, as NGFF lists axes), and under the group's "volren" key every brick's value range, so that
a renderer can skip bricks a TF makes transparent without reading them.

Reading (`open_multiscale`, `load_level`): the metadata alone first; a level's values brick by
brick, so that a corrupt brick is a one-line error naming it. Images with time or channel axes are
read when those axes have one entry; a channel (c) axis of several is read whole, the channels
picked, as a multi-channel volume (`load_channels`: ``omero.channels``' colours, windows, labels
and active flags), and refused by the bricked path, which streams one field. A time (t) axis of
several is a time series (`volren.io.series_io`): each step, ``image.zarr#t=N``, reads that time
point alone, whole or streamed, with its channels if asked. Local folders and fsspec URLs
(http://, s3://, ...) both work: zarr opens either.
"""

from __future__ import annotations

import json
import math
import os
import re
import shutil
import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from volren.errors import VolrenError, VolrenWarning
from volren.heap import release_free_heap
from volren.model.pyramid import (
    DEFAULT_CHUNK,
    MAX_CHUNK,
    MIN_CHUNK,
    block_mean,
    brick_slices,
    coarser_placement,
    default_levels,
    level_shapes,
    value_range,
)
from volren.model.volume import UniformVolume

#: The install hint of the optional packages this format needs.
INSTALL_HINT = "pip install 'volren[zarr]'"
#: Under this key of the group's attributes: what volren adds to NGFF (brick value ranges).
VOLREN_KEY = "volren"
NGFF_WRITTEN = "0.4"
#: A level read into memory whole is refused above this many bytes (ask for a coarser level).
MAX_IN_MEMORY_BYTES = 8 << 30
#: Voxels placed farther from the origin are refused: far beyond any instrument's reach, and far
#: enough inside a float's range that the camera's squares and sums of them stay finite.
MAX_COORDINATE = 1e100

#: progress(fraction done) while writing.
Progress = Callable[[float], None]


def require_zarr() -> Any:
    try:
        import zarr
    except ImportError:
        raise VolrenError(f"OME-Zarr needs zarr, which is not installed: {INSTALL_HINT}") from None
    return zarr


def is_url(path: str | Path) -> bool:
    return "://" in str(path)


#: Seconds an HTTP(S) read may wait to connect, and then between two packets of an answer, before
#: a one-line error: no hang on a server that does not answer.
URL_TIMEOUT_S = 30.0


def _store_options(where: str) -> dict[str, Any]:
    """fsspec options for `where`: time limits on connecting and on every read of an HTTP(S)
    answer (aiohttp waits 5 minutes by default, which looks like a hang). A chunk that keeps
    arriving may take longer than that in all: a slow link is not an error."""
    if not where.lower().startswith(("http://", "https://")):
        return {}
    try:
        import aiohttp
    except ImportError:
        raise VolrenError(
            f"{where}: reading over HTTP needs aiohttp, which is not installed: {INSTALL_HINT}"
        ) from None

    timeout = aiohttp.ClientTimeout(total=None, connect=URL_TIMEOUT_S, sock_read=URL_TIMEOUT_S)
    return {"storage_options": {"client_kwargs": {"timeout": timeout}}}


def _client_errors() -> tuple[type[BaseException], ...]:
    """aiohttp's errors (HTTP statuses, redirect loops, answers cut short), when it is installed."""
    try:
        import aiohttp
    except ImportError:
        return ()
    return (aiohttp.ClientError,)


def _read_errors() -> tuple[type[BaseException], ...]:
    """What reading an image's metadata raises for bad bytes or a failing store or server."""
    return (OSError, TimeoutError, KeyError, TypeError, ValueError, *_client_errors())


def server_problem(exc: BaseException) -> str | None:
    """What a server did wrong, in words (None: `exc` is not about a server)."""
    if isinstance(exc, TimeoutError):
        return f"the server did not answer within {URL_TIMEOUT_S:g} s"
    try:
        import aiohttp
    except ImportError:
        return None
    if isinstance(exc, aiohttp.TooManyRedirects):
        return "the server redirected too many times (a redirect loop)"
    if isinstance(exc, aiohttp.ClientResponseError):
        return f"the server answered HTTP {exc.status} {exc.message or ''}".rstrip()
    if isinstance(exc, aiohttp.ClientPayloadError):
        return "the server's answer was cut short"
    if isinstance(exc, aiohttp.ClientError):
        return f"the server cannot be reached: {_first_words(exc)}"
    return None


def _first_words(exc: BaseException, limit: int = 200) -> str:
    """An exception's message on one line, shortened; what it is when it has none (never its class)."""
    text = " ".join(str(exc).split())[:limit]
    return text or "no reason given"


def read_problem(exc: BaseException) -> str:
    """Why part of an image cannot be read, in words: a server's failure or the reader's message."""
    if isinstance(exc, json.JSONDecodeError):
        return f"its metadata is not valid JSON ({exc.msg} at line {exc.lineno})"
    return server_problem(exc) or _first_words(exc)


#: How one time point of an image with a t axis is named: ``image.zarr#t=3`` (a time series' step).
_TIME_POINT = re.compile(r"#t=(\d+)$")


def split_time_point(path: str | Path) -> tuple[str, int | None]:
    """(the image's own path, the time point named after it, or None): ``a.zarr#t=3`` is time point 3
    of ``a.zarr``. A path that exists as written is never split (a folder may have '#' in its name)."""
    text = str(path)
    match = _TIME_POINT.search(text)
    if match is None or (not is_url(text) and Path(text).exists()):
        return text, None
    return text[: match.start()], int(match.group(1))


def time_point_path(path: str | Path, index: int) -> str:
    """The name of time point `index` of the image at `path` (`split_time_point` reads it back)."""
    return f"{split_time_point(path)[0]}#t={index}"


def is_ome_zarr(path: str | Path) -> bool:
    """A folder (or URL) holding a Zarr group, taken as an OME-Zarr image: Zarr v2 (.zgroup or
    .zattrs) or v3 (zarr.json), or a URL naming a .zarr. One without OME metadata is then an error
    that says so, not a DICOM folder that is not one. ``image.zarr#t=3`` (one time point of it) is
    one too."""
    path = split_time_point(path)[0]
    if is_url(path):
        return str(path).rstrip("/").lower().endswith(".zarr")
    path = Path(path)
    return path.is_dir() and any((path / name).is_file() for name in (".zgroup", ".zattrs", "zarr.json"))


# ------------------------------------------------------------------------------------ reading
@dataclass(frozen=True)
class LevelInfo:
    """One level's array key, shape (z, y, x), brick shape, and voxel placement (x, y, z)."""

    key: str
    shape: tuple[int, int, int]
    chunks: tuple[int, int, int]
    spacing: tuple[float, float, float]
    origin: tuple[float, float, float]
    dtype: np.dtype
    #: what a brick without a chunk file reads as
    fill_value: float = 0.0
    #: the sizes of the leading axes (time, channel) before z, y, x
    leading_shape: tuple[int, ...] = ()


@dataclass(frozen=True)
class Multiscale:
    """An opened OME-Zarr image: its levels (finest first) and, if volren wrote it, the value
    range of every brick of every level (None for a brick with no finite value)."""

    path: str
    name: str
    levels: tuple[LevelInfo, ...]
    brick_ranges: tuple[tuple[tuple[float, float] | None, ...], ...] | None
    #: leading singleton axes (time, channel) to drop from each array's index
    leading: int = 0
    #: the leading axes' names, and the image's channels (the c axis' size; 1 without one)
    leading_axes: tuple[str, ...] = ()
    channel_count: int = 1
    #: the group's "omero" attributes (channel colours, windows, labels), if any
    omero: Mapping[str, Any] | None = None
    #: the time point read (on a t axis) and the times of all of them (the t axis' scale and
    #: translation; (0.0,) without a t axis)
    time: int = 0
    times: tuple[float, ...] = (0.0,)

    def array(self, level: int) -> Any:
        """The zarr array of `level` (lazy: nothing is read until it is indexed)."""
        key = self.levels[level].key
        try:
            return _open_level_array(self.path, key)
        except VolrenError as exc:
            raise VolrenError(f"{self.path}: {exc}") from None


def _open_level_array(where: str, key: str) -> Any:
    """The zarr array of the level stored under `key`; one line naming the level when it cannot be opened."""
    zarr = require_zarr()
    try:
        return zarr.open_array(f"{where.rstrip('/')}/{key}", mode="r", **_store_options(where))
    except (FileNotFoundError, KeyError):
        raise VolrenError(f"level {key!r} is listed but missing") from None
    except _read_errors() as exc:
        raise VolrenError(f"level {key!r} cannot be opened: {read_problem(exc)}") from None


def _multiscales(attrs: Mapping[str, Any]) -> tuple[Mapping[str, Any], str]:
    ome = attrs.get("ome")
    if isinstance(ome, Mapping) and isinstance(ome.get("multiscales"), list) and ome["multiscales"]:
        found, version = ome["multiscales"][0], str(ome.get("version", "0.5"))
        if isinstance(found, Mapping):
            return found, version
    found = attrs.get("multiscales")
    if isinstance(found, list) and found and isinstance(found[0], Mapping):
        return found[0], str(found[0].get("version", ""))
    raise VolrenError("not an OME-Zarr image: no 'multiscales' in the group's attributes")


def _axes(meta: Mapping[str, Any]) -> list[str]:
    """The axis names, the last three of which must be z, y, x."""
    listed = meta.get("axes", ["z", "y", "x"])
    if not isinstance(listed, list):
        raise VolrenError(f"'axes' must be a list of axes, got {_shown(listed)}")
    axes: list[Any] = [a.get("name") if isinstance(a, Mapping) else a for a in listed]
    if axes[-3:] != ["z", "y", "x"]:
        raise VolrenError(f"axes {_shown(axes)}: volren reads volumes whose last three axes are z, y, x")
    return axes


def _shown(value: Any, limit: int = 80) -> str:
    """A metadata value as the message shows it (shortened)."""
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _finite(value: int | float) -> bool:
    """math.isfinite, False for an integer beyond float64 (JSON's integers have any size)."""
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


def _numbers(values: Any, axes: int, what: str) -> list[float]:
    """`axes` finite numbers (bools and text refused: JSON's true is not a scale)."""
    numeric = isinstance(values, list) and all(
        isinstance(v, int | float) and not isinstance(v, bool) for v in values
    )
    if not numeric or len(values) != axes or not all(_finite(v) for v in values):
        raise VolrenError(f"its {what} must be a list of {axes} finite numbers, got {_shown(values)}")
    return [float(v) for v in values]


def _transforms(dataset: Mapping[str, Any], axes: int) -> tuple[list[float], list[float]]:
    scale, translation = [1.0] * axes, [0.0] * axes
    transforms = dataset.get("coordinateTransformations", [])
    try:
        if not isinstance(transforms, list) or not all(isinstance(t, Mapping) for t in transforms):
            raise VolrenError(
                f"its coordinateTransformations must be a list of objects, got {_shown(transforms)}"
            )
        for transform in transforms:
            kind = transform.get("type")
            if kind == "scale":
                scale = _numbers(transform.get("scale"), axes, "scale")
            elif kind == "translation":
                translation = _numbers(transform.get("translation"), axes, "translation")
        if any(v <= 0 for v in scale):
            raise VolrenError(f"scale must be positive, got {scale}")
    except VolrenError as exc:
        raise VolrenError(f"level {dataset.get('path')!r}: {exc}") from None
    return scale, translation


def _level(where: str, dataset: Any, axes: list[str]) -> LevelInfo:
    """One entry of 'datasets': its array opened and checked against the axes and transforms."""
    if not isinstance(dataset, Mapping) or not isinstance(dataset.get("path"), str | int):
        raise VolrenError(f"each of 'datasets' must be an object with a 'path', got {_shown(dataset)}")
    key = str(dataset["path"])
    array = _open_level_array(where, key)
    leading = len(axes) - 3
    if array.ndim != len(axes):
        raise VolrenError(f"level {key!r} has {array.ndim} axes, the metadata {len(axes)}")
    shape, chunks = tuple(array.shape[leading:]), tuple(array.chunks[leading:])
    if min(shape) < 1 or min(chunks) < 1:
        raise VolrenError(
            f"level {key!r}: its shape {shape} and chunk shape {chunks} must have no empty side"
        )
    scale, translation = _transforms(dataset, len(axes))
    ends = [t + h * (n - 1) for h, t, n in zip(scale[leading:], translation[leading:], shape, strict=True)]
    if not all(abs(v) <= MAX_COORDINATE for v in (*translation[leading:], *ends)):
        raise VolrenError(f"level {key!r}: its scale {scale} and translation {translation} place voxels beyond "
                          f"+-{MAX_COORDINATE:g}")  # fmt: skip
    spacing, origin = (scale[-1], scale[-2], scale[-3]), (translation[-1], translation[-2], translation[-3])
    return LevelInfo(key, shape, chunks, spacing, origin, np.dtype(array.dtype), _number_or_zero(array.fill_value),
                     tuple(int(n) for n in array.shape[:leading]))  # fmt: skip


def _channel_count(
    axes: list[str], levels: Sequence[LevelInfo], channels_ok: bool, times_ok: bool = False
) -> int:
    """The size of the c axis (1 without one); leading axes of several entries other than c and t, c
    where channels are not asked for, and t where no time point is named, refused in one line."""
    lead = axes[:-3]
    first = levels[0].leading_shape
    for level in levels[1:]:
        if level.leading_shape != first:
            raise VolrenError(f"level {level.key!r} has {level.leading_shape} entries on axes {lead}, "
                              f"level {levels[0].key!r} {first}: the levels must agree")  # fmt: skip
    count = 1
    for axis, n in zip(lead, first, strict=True):
        if n == 1:
            continue
        if axis == "t":
            if times_ok:
                continue
            raise VolrenError(f"axis 't' holds {n} time points; volren reads one time point at a time: open the "
                              "image as a time series, or name one as IMAGE.zarr#t=N")  # fmt: skip
        if axis != "c":
            raise VolrenError(f"axis {axis!r} holds {n} entries; volren reads one volume of it")
        if not channels_ok:
            raise VolrenError(f"axis 'c' holds {n} channels; pick them with --channels (Python: channels=) to draw "
                              "them read whole as a multi-channel volume (not streamed by bricks)")  # fmt: skip
        count = n
    return count


def open_multiscale(path: str | Path, channels_ok: bool = False, times_ok: bool = False) -> Multiscale:
    """The metadata of the OME-Zarr image at `path`; one-line errors name the path and the problem.
    An image of several channels (a c axis) is refused unless `channels_ok` (`load_channels`); one
    of several time points (a t axis) unless `path` names one (``image.zarr#t=3``: read as a time
    series' step, `volren.io.series_io`) or `times_ok` (its metadata only: time point 0 is read)."""
    zarr = require_zarr()
    where, time = split_time_point(path)
    try:
        group = zarr.open_group(where, mode="r", **_store_options(where))
        attrs = dict(group.attrs)
        meta, _version = _multiscales(attrs)
        axes = _axes(meta)
        datasets = meta.get("datasets", [])
        if not isinstance(datasets, list):
            raise VolrenError(f"'datasets' must be a list of levels, got {_shown(datasets)}")
        levels = [_level(where, dataset, axes) for dataset in datasets]
        if not levels:
            raise VolrenError("the multiscale image lists no levels")
        count = _channel_count(axes, levels, channels_ok, times_ok or time is not None)
        times = _times(axes, levels[0], datasets[0])
        if time is not None and time >= len(times):
            raise VolrenError(f"no time point {time}; the image has time points 0 to {len(times) - 1}")
        ranges = _brick_ranges(attrs.get(VOLREN_KEY), levels)
        _check_chunk_files(where, levels, ranges)
    except VolrenError as exc:
        raise VolrenError(f"{where}: {exc}") from None
    except _read_errors() as exc:
        problem = server_problem(exc)
        raise VolrenError(
            f"{where}: {problem or 'not a readable OME-Zarr image: ' + read_problem(exc)}"
        ) from None
    name = meta.get("name")
    shown = str(name) if isinstance(name, str | int) and str(name) else Path(where.rstrip("/")).name
    omero = attrs.get("omero") or (attrs.get("ome") or {}).get("omero")
    return Multiscale(where, shown, tuple(levels), ranges, len(axes) - 3, tuple(axes[:-3]), count,
                      omero if isinstance(omero, Mapping) else None, time or 0, times)  # fmt: skip


def _times(axes: list[str], level: LevelInfo, dataset: Mapping[str, Any]) -> tuple[float, ...]:
    """The time of each time point: the t axis' scale and translation of the finest level (NGFF's
    coordinateTransformations cover every axis); (0.0,) without a t axis."""
    if "t" not in axes[:-3]:
        return (0.0,)
    axis = axes.index("t")
    scale, translation = _transforms(dataset, len(axes))
    return tuple(translation[axis] + scale[axis] * k for k in range(level.leading_shape[axis]))


def _brick_range(entry: Any) -> tuple[float, float] | None:
    """One stored brick range: None (no finite value) or [min, max], two finite numbers in order."""
    if entry is None:
        return None
    numeric = isinstance(entry, list) and all(
        isinstance(v, int | float) and not isinstance(v, bool) for v in entry
    )
    if not numeric or len(entry) != 2 or not all(_finite(v) for v in entry) or entry[0] > entry[1]:
        raise VolrenError(f"a brick range must be null or [min, max], got {_shown(entry)}")
    return float(entry[0]), float(entry[1])


def _brick_ranges(extra: Any, levels: Sequence[LevelInfo]) -> tuple | None:
    """volren's stored brick ranges, checked against each level's brick grid."""
    if not isinstance(extra, Mapping) or "brick_ranges" not in extra:
        return None
    stored = extra["brick_ranges"]
    if not isinstance(stored, list) or len(stored) != len(levels):
        raise VolrenError(f"'{VOLREN_KEY}.brick_ranges' lists {len(stored) if isinstance(stored, list) else 'no'} "
                          f"levels, the image {len(levels)}")  # fmt: skip
    out = []
    for level, ranges in zip(levels, stored, strict=True):
        bricks = math.prod(math.ceil(n / c) for n, c in zip(level.shape, level.chunks, strict=True))
        if not isinstance(ranges, list) or len(ranges) != bricks:
            raise VolrenError(f"level {level.key!r}: its chunk shape {level.chunks} makes {bricks} bricks, the stored "
                              f"ranges are for {len(ranges) if isinstance(ranges, list) else 'no'}")  # fmt: skip
        try:
            out.append(tuple(_brick_range(r) for r in ranges))
        except VolrenError as exc:
            raise VolrenError(f"'{VOLREN_KEY}.brick_ranges' of level {level.key!r}: {exc}") from None
    return tuple(out)


def _check_chunk_files(where: str, levels: Sequence[LevelInfo], ranges: tuple | None) -> None:
    """A local level without a single chunk file reads as its fill value everywhere: an error
    when volren's stored ranges say it held other values (its chunks were lost), else a warning
    (a reader cannot tell an image of fill values from one whose chunks are missing).
    Over a URL, chunks cannot be listed: nothing is checked."""
    if is_url(where):
        return
    for index, level in enumerate(levels):
        if _has_chunk_files(Path(where) / level.key):
            continue
        fill = level.fill_value
        stored = [r for r in ranges[index] if r is not None] if ranges is not None else None
        if stored and any(r != (fill, fill) for r in stored):
            high = max(r[1] for r in stored)
            raise VolrenError(f"level {level.key!r} has no chunk files, yet its stored brick ranges reach {high:g}: "
                              f"its chunks are missing")  # fmt: skip
        if stored is None:
            warnings.warn(f"{where}: level {level.key!r} has no chunk files: every value reads as its fill value "
                          f"{fill:g}", VolrenWarning, stacklevel=3)  # fmt: skip


def _has_chunk_files(folder: Path) -> bool:
    """Whether a local level's folder holds anything but metadata (Zarr v2's dot files, v3's zarr.json)."""
    try:
        return any(
            not entry.name.startswith(".") and entry.name != "zarr.json" for entry in os.scandir(folder)
        )
    except OSError:
        return True  # a level kept elsewhere (a link, an archive): nothing to say


def _number_or_zero(value: Any) -> float:
    """A fill value as a number (zarr's default, 0, for none or one that is not a number)."""
    try:
        return float(value) if value is not None else 0.0
    except (TypeError, ValueError):
        return 0.0


def level_bytes(level: LevelInfo, copies_per_voxel: int = 0) -> int:
    """The bytes of a level's values, and of `copies_per_voxel` more bytes a voxel (what a
    renderer's own copies of a level read whole take: `zarr_input.renderer_copy_bytes`)."""
    return math.prod(level.shape) * (level.dtype.itemsize + copies_per_voxel)


def finest_level_within(image: Multiscale, budget: int, copies_per_voxel: int = 0) -> int | None:
    """The finest level whose values (and copies, `level_bytes`) take at most `budget` bytes
    (None: not even the coarsest)."""
    return next(
        (k for k, level in enumerate(image.levels) if level_bytes(level, copies_per_voxel) <= budget), None
    )


def finest_level_said(
    image: Multiscale, budget: int, name: str, why: str = "", copies_per_voxel: int = 0
) -> int | None:
    """`finest_level_within`, with a one-line warning (naming `name`, and `why` after it) when
    that is not the full resolution."""
    level = finest_level_within(image, budget, copies_per_voxel)
    if level:
        whole = human_size(level_bytes(image.levels[0]))
        drawn = (
            f" ({human_size(level_bytes(image.levels[0], copies_per_voxel))} drawn)"
            if copies_per_voxel
            else ""
        )
        warnings.warn(f"{name}: its full resolution is {whole}{drawn}, more than the {human_size(budget)} allowed; "
                      f"rendering level {level}, the finest that fits{why}", VolrenWarning, stacklevel=3)  # fmt: skip
    return level


def human_size(size: float) -> str:
    """Bytes as people read them: 512 KiB, 16.0 MiB, 1.5 GiB."""
    for unit, scale in (("GiB", 1 << 30), ("MiB", 1 << 20), ("KiB", 1 << 10)):
        if size >= scale:
            return f"{size / scale:.1f} {unit}"
    return f"{int(size)} bytes"


def parse_memory(text: str) -> int:
    """Bytes from "2GB", "512MB", "1.5GiB", "800k" or a plain number of bytes."""
    units = {"": 1, "k": 1 << 10, "m": 1 << 20, "g": 1 << 30, "t": 1 << 40}
    cleaned = text.strip().lower().removesuffix("ib").removesuffix("b")
    number, unit = (cleaned[:-1], cleaned[-1]) if cleaned and cleaned[-1] in "kmgt" else (cleaned, "")
    try:
        value = float(number) * units[unit]
    except ValueError:
        raise VolrenError(f"a memory size must look like 2GB, 512MB or 1.5GiB, got {text!r}") from None
    if not math.isfinite(value) or value < 1:
        raise VolrenError(f"a memory size must be positive, got {text!r}")
    return int(value)


def load_level(path: str | Path, level: int | None = 0, name: str | None = None,
               memory: int = MAX_IN_MEMORY_BYTES) -> UniformVolume:  # fmt: skip
    """Level `level` of the image at `path` (0: full resolution; None: the finest that fits in
    `memory` bytes), read brick by brick into memory."""
    image = open_multiscale(path)
    if level is None:
        level = finest_level_within(image, memory)
        if level is None:
            coarsest = image.levels[-1]
            raise VolrenError(f"{path}: even the coarsest level ({human_size(level_bytes(coarsest))}) is more than "
                              f"the memory allowed ({human_size(memory)})")  # fmt: skip
    if not 0 <= level < len(image.levels):
        raise VolrenError(f"{path}: no level {level}; the image has levels 0 to {len(image.levels) - 1}")
    info = image.levels[level]
    size = level_bytes(info)
    limit = min(memory, MAX_IN_MEMORY_BYTES)
    if size > limit:
        coarse = finest_level_within(image, limit)
        hint = f"; level {coarse} fits" if coarse is not None else ""
        raise VolrenError(f"{path}: level {level} is {human_size(size)}, more than the {human_size(limit)} allowed "
                          f"read whole{hint}")  # fmt: skip
    array = image.array(level)
    values = np.empty(info.shape, info.dtype)
    for index, where in _level_bricks(info):
        values[where] = read_brick(image, level, array, index)
    return UniformVolume(values, info.spacing, info.origin, name=name or image.name)


def read_brick(
    image: Multiscale, level: int, array: Any, index: tuple[int, ...], channel: int = 0
) -> np.ndarray:
    """The values of brick (chunk) `index` (kz, ky, kx) of `level` (of `channel`, on a c axis),
    whose zarr array is `array`; a brick that cannot be read is a one-line error naming it."""
    info = image.levels[level]
    where = tuple(
        slice(k * c, min((k + 1) * c, n)) for k, c, n in zip(index, info.chunks, info.shape, strict=True)
    )
    try:
        lead = (
            tuple(channel if axis == "c" else image.time if axis == "t" else 0 for axis in image.leading_axes)
            or (0,) * image.leading
        )
        return np.asarray(array[lead + where])
    except Exception as exc:  # noqa: BLE001 - a codec's error, whatever its type, names the brick
        key = ".".join(str(k) for k in index)
        raise VolrenError(
            f"{image.path}: level {info.key!r}, brick {key}: cannot be read: {read_problem(exc)}"
        ) from None


def _level_bricks(info: LevelInfo) -> Iterator[tuple[tuple[int, ...], tuple[slice, ...]]]:
    """(brick index, its slices) over a level, for any brick shape."""
    counts = [math.ceil(n / c) for n, c in zip(info.shape, info.chunks, strict=True)]
    for index in np.ndindex(*counts):
        yield index, tuple(slice(k * c, min((k + 1) * c, n)) for k, c, n in zip(index, info.chunks, info.shape,
                                                                                   strict=True))  # fmt: skip


# ------------------------------------------------------------------------------------ writing
def save_ome_zarr(volume: UniformVolume, path: str | Path, chunk: int = DEFAULT_CHUNK, levels: int | None = None,
                  progress: Progress | None = None) -> int:  # fmt: skip
    """Write `volume` as an OME-Zarr pyramid at `path` (a new folder; an old one is replaced only
    once the new one is complete); returns the number of levels written."""
    return write_pyramid(
        volume.values, volume.spacing, volume.origin, volume.name, path, chunk, levels, progress
    )


def write_pyramid(values: Any, spacing: Sequence[float], origin: Sequence[float], name: str, path: str | Path,
                  chunk: int = DEFAULT_CHUNK, levels: int | None = None, progress: Progress | None = None) -> int:  # fmt: skip
    """Write the pyramid of `values` (z, y, x): a numpy array, or anything with `shape`, `dtype`
    and numpy slicing, such as a volume generated a block at a time. Memory stays bounded by a few
    bricks: level 0 is copied brick by brick, and each coarser level is made brick by brick from
    the level below as written (2x2x2 block means, `model.pyramid`)."""
    zarr = require_zarr()
    path = Path(path)
    if not (isinstance(chunk, int) and MIN_CHUNK <= chunk <= MAX_CHUNK):
        raise VolrenError(f"{path}: bricks must be {MIN_CHUNK} to {MAX_CHUNK} samples a side, got {chunk!r}")
    shape = tuple(int(n) for n in values.shape)
    count = levels if levels is not None else default_levels(shape, chunk)
    if not path.absolute().parent.is_dir():
        raise VolrenError(f"{path}: the folder {path.absolute().parent} does not exist")
    shapes = level_shapes(shape, count)
    partial = path.with_name(f".{path.name}.partial")
    shutil.rmtree(partial, ignore_errors=True)
    total = sum(_bricks(level_shape, chunk) for level_shape in shapes)
    done = 0
    try:
        group = zarr.open_group(str(partial), mode="w", zarr_format=2)
        datasets, ranges = [], []
        below = None
        level_spacing, level_origin = tuple(float(v) for v in spacing), tuple(float(v) for v in origin)
        for index, level_shape in enumerate(shapes):
            if index:
                level_spacing, level_origin = coarser_placement(level_spacing, level_origin)
            array = group.create_array(str(index), shape=level_shape, chunks=(chunk,) * 3, dtype=np.dtype(values.dtype),
                                       fill_value=0)  # fmt: skip
            level_ranges = []
            for _, where in brick_slices(level_shape, chunk):
                if below is None:
                    brick = np.asarray(values[where])
                else:  # the block means of the 2x larger block below (its odd last samples left out)
                    release_free_heap()  # the last block's pages, which a fragmented heap would keep
                    brick = block_mean(
                        np.asarray(below[tuple(slice(2 * w.start, 2 * w.stop) for w in where)])
                    )
                array[where] = brick
                level_ranges.append(value_range(brick))
                done += 1
                if progress is not None:
                    progress(min(done / total, 1.0))
            below = array
            ranges.append(level_ranges)
            datasets.append(
                {
                    "path": str(index),
                    "coordinateTransformations": [
                        {"type": "scale", "scale": list(level_spacing[::-1])},
                        {"type": "translation", "translation": list(level_origin[::-1])},
                    ],
                }
            )
        group.attrs["multiscales"] = [
            {
                "version": NGFF_WRITTEN,
                "name": name,
                "type": "2x2x2 block mean",
                "axes": [{"name": a, "type": "space"} for a in "zyx"],
                "datasets": datasets,
            }
        ]
        group.attrs[VOLREN_KEY] = {"version": 1, "brick_ranges": [[None if r is None else list(r) for r in level]
                                                                    for level in ranges]}  # fmt: skip
    except VolrenError:
        shutil.rmtree(partial, ignore_errors=True)
        raise
    except (OSError, ValueError) as exc:
        shutil.rmtree(partial, ignore_errors=True)
        raise VolrenError(
            f"{path}: cannot write the OME-Zarr image: {' '.join(str(exc).split())[:200]}"
        ) from None
    except BaseException:
        shutil.rmtree(partial, ignore_errors=True)
        raise
    if path.is_dir():
        shutil.rmtree(path)
    elif path.exists():
        path.unlink()
    partial.rename(path)
    return count


def _bricks(shape, chunk: int) -> int:
    return math.prod(math.ceil(n / chunk) for n in shape)


# ---------------------------------------------------------------------------- channels (c axis)
def load_channels(path: str | Path, pick: Any, level: int | None = None, name: str | None = None,
                  memory: int = MAX_IN_MEMORY_BYTES) -> UniformVolume:  # fmt: skip
    """The channels `pick` names (True: all; else the c axis' numbers) of level `level` of the
    image at `path` (None: the finest whose picked channels fit in `memory` bytes), read brick by
    brick into memory as a multi-channel volume: names, colours, windows and active flags from
    ``omero.channels`` (`volren.io.omero_channels`), `values` the first active channel picked."""
    from volren.io.channel_io import PickedChannels, check_pick, first_shown, nonfinite_notes
    from volren.io.omero_channels import channel_hints

    image = open_multiscale(path, channels_ok=True)
    if "c" not in image.leading_axes:
        raise VolrenError(f"{path}: the image has no channel axis (c); it holds one field")
    picked = check_pick(pick, image.channel_count, f"{path}: the image has {image.channel_count} channels")
    shown = name or image.name
    copies = image.levels[0].dtype.itemsize * (len(picked) - 1)  # the other channels' bytes a voxel
    if level is None:
        level = finest_level_said(image, memory, shown, f" ({len(picked)} channels)", copies)
        if level is None:
            coarsest = level_bytes(image.levels[-1]) * len(picked)
            raise VolrenError(f"{path}: even the coarsest level's {len(picked)} channels ({human_size(coarsest)}) are "
                              f"more than the memory allowed ({human_size(memory)})")  # fmt: skip
    if not 0 <= level < len(image.levels):
        raise VolrenError(f"{path}: no level {level}; the image has levels 0 to {len(image.levels) - 1}")
    info = image.levels[level]
    size, limit = level_bytes(info) * len(picked), min(memory, MAX_IN_MEMORY_BYTES)
    if size > limit:
        raise VolrenError(f"{path}: level {level}'s {len(picked)} channels are {human_size(size)}, more than the "
                          f"{human_size(limit)} allowed read whole; pick fewer channels or a coarser level")  # fmt: skip
    array = image.array(level)
    values = np.empty((len(picked), *info.shape), info.dtype)
    for slot, channel in enumerate(picked):
        for index, where in _level_bricks(info):
            values[slot][where] = read_brick(image, level, array, index, channel)
    hints = [channel_hints(image.omero, image.channel_count)[c] for c in picked]
    channels = PickedChannels(
        values,
        tuple(h.name or f"channel {c}" for h, c in zip(hints, picked, strict=True)),
        tuple(h.color for h in hints),
        tuple(h.window for h in hints),
        name=shown,
        indices=picked,
        active=tuple(h.active for h in hints),
    )
    for note in nonfinite_notes(channels, shown):
        warnings.warn(note, VolrenWarning, stacklevel=2)
    return UniformVolume(channels.values[first_shown(channels)], info.spacing, info.origin, name=shown,
                         channels=channels)  # fmt: skip
