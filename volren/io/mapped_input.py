"""Volumes read a row of bricks at a time from their file, never whole: what `volren convert`
streams into a pyramid, so that a volume larger than memory converts.

Which inputs: those whose values lie uncompressed on disk, x fastest, at an offset the header
gives (NRRD with raw encoding, MetaImage with uncompressed data) or the caller does (headerless
raw data, `open_raw`), on an axis-aligned grid with positive spacings and one scalar field. Anything else (a rotated or mirrored grid, compressed or
text data, other formats) is read whole by `load_volume`, whose readers know those cases: the
grid `open_mapped` describes is exactly the one `load_volume` makes (the tests compare pyramids).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from numpy.typing import DTypeLike, NDArray

from volren.heap import release_free_heap
from volren.io.formats import find_format
from volren.io.formats.base import is_identity
from volren.io.formats.geometry import parse_numbers
from volren.io.formats.raw import check_raw_size, raw_layout
from volren.io.limits import check_layout
from volren.model.volume import normalize_dtype

Triple = tuple[float, float, float]

_MET_TYPES = {
    "MET_CHAR": "i1", "MET_UCHAR": "u1", "MET_SHORT": "i2", "MET_USHORT": "u2", "MET_INT": "i4", "MET_UINT": "u4",
    "MET_LONG": "i4", "MET_ULONG": "u4", "MET_LONG_LONG": "i8", "MET_ULONG_LONG": "u8", "MET_FLOAT": "f4",
    "MET_DOUBLE": "f8",
}  # fmt: skip


@dataclass(frozen=True)
class MappedVolume:
    """Where a volume's values lie in its file, and the grid they sample."""

    name: str
    data_file: Path
    offset: int
    #: the values' type as stored (byte order included)
    stored: np.dtype
    #: (z, y, x)
    shape: tuple[int, int, int]
    spacing: Triple
    origin: Triple

    @property
    def dtype(self) -> np.dtype:
        """The type the model keeps the values in (`normalize_dtype`: int8 as int16, ...)."""
        values, _ = normalize_dtype(np.zeros(1, self.stored.newbyteorder("=")), self.name)
        return values.dtype

    def row_bytes(self, rows: int) -> int:
        """Bytes of a row of bricks `rows` samples high and deep (as stored and as kept)."""
        nz, ny, nx = self.shape
        return min(rows, nz) * min(rows, ny) * nx * (self.stored.itemsize + self.dtype.itemsize)


def open_mapped(path: Path) -> MappedVolume | None:
    """The volume in `path` as a `MappedVolume`, or None when it must be read whole."""
    if not path.is_file():
        return None
    fmt = find_format(path)
    if fmt is None or fmt.name not in ("NRRD", "MetaImage"):
        return None
    inspection = fmt.inspect(path)
    layout = inspection.layout
    if layout is None or layout.data_file is None or len(layout.shape) != 3:
        return None
    check_layout(path, replace(layout, memory_bytes=0))  # all its bytes are there; memory is not needed
    geometry = _nrrd_geometry(path, inspection.facts) if fmt.name == "NRRD" else _metaimage_geometry(path)
    if geometry is None:
        return None
    stored, spacing, origin = geometry
    nx, ny, nz = layout.shape
    return MappedVolume(
        path.name, layout.data_file, layout.data_offset, stored, (nz, ny, nx), spacing, origin
    )


def open_raw(
    path: Path,
    shape: Sequence[int],
    dtype: DTypeLike | None = None,
    byte_order: str = "little",
    spacing: Sequence[float] = (1.0, 1.0, 1.0),
    origin: Sequence[float] = (0.0, 0.0, 0.0),
    header_bytes: int = 0,
) -> MappedVolume | None:
    """Headerless raw data (`load_volume`'s arguments for it) as a `MappedVolume`, checked as
    `load_raw` checks it, memory aside; None for a grid the reader must place (a spacing not
    positive, a placement not finite)."""
    (nx, ny, nz), stored = raw_layout(path, shape, dtype, byte_order, header_bytes)
    check_raw_size(path, (nx, ny, nz), stored, header_bytes)
    spacing_xyz, origin_xyz = _finite_triple(spacing), _finite_triple(origin)
    if spacing_xyz is None or origin_xyz is None or min(spacing_xyz) <= 0:
        return None
    return MappedVolume(path.name, path, header_bytes, stored, (nz, ny, nx), spacing_xyz, origin_xyz)


def _finite_triple(values: Sequence[float]) -> Triple | None:
    """Three finite numbers as floats, or None (then the whole read's checks speak)."""
    try:
        triple = tuple(float(v) for v in values)
    except (TypeError, ValueError, OverflowError):
        return None
    return triple if len(triple) == 3 and all(map(math.isfinite, triple)) else None  # type: ignore[return-value]


def _nrrd_geometry(path: Path, facts: dict) -> tuple[np.dtype, Triple, Triple] | None:
    """(stored type, spacing, origin) of a NRRD file on three spatial axes, or None for one the
    reader must place (mirrored rows, a direction matrix, negative spacings)."""
    from volren.io.formats.nrrd import _SPATIAL_KINDS, _header, _text_dtype

    fields, _ = _header(path)
    kinds = fields.get("kinds", "").lower().split()
    spacing = tuple(facts["spacing"])
    if (
        any(k not in _SPATIAL_KINDS for k in kinds)
        or "flip_axis" in facts
        or not is_identity(facts["direction"])
    ):
        return None
    if len(spacing) != 3 or min(spacing) <= 0 or "axismins" in fields:
        return None
    stored = _text_dtype(fields["type"].lower())
    if stored.itemsize > 1:
        stored = stored.newbyteorder(">" if fields.get("endian", "little").lower() == "big" else "<")
    origin = parse_numbers(path, "space origin", fields.get("spaceorigin")) or (0.0, 0.0, 0.0)
    return stored, spacing, origin  # type: ignore[return-value]


def _metaimage_geometry(path: Path) -> tuple[np.dtype, Triple, Triple] | None:
    """(stored type, spacing, origin) of a one-channel MetaImage file, or None for one the reader
    must place (a direction matrix, negative or absent spacings)."""
    from volren.io.formats.metaimage import _header

    fields, _ = _header(path)
    if int(fields.get("elementnumberofchannels", "1")) != 1 or "elementspacing" not in fields:
        return None
    spacing = parse_numbers(path, "ElementSpacing", fields["elementspacing"])
    matrix = fields.get("transformmatrix")
    if spacing is None or min(spacing) <= 0 or (matrix is not None and not _is_identity_text(matrix)):
        return None
    origin_key = next((k for k in ("offset", "origin", "position") if k in fields), "offset")
    origin = parse_numbers(path, origin_key.capitalize(), fields.get(origin_key)) or (0.0, 0.0, 0.0)
    stored = np.dtype(_MET_TYPES[fields["elementtype"].upper()])
    msb = (
        fields.get("elementbyteordermsb") or fields.get("binarydatabyteordermsb") or "false"
    ).lower() == "true"
    if stored.itemsize > 1:
        stored = stored.newbyteorder(">" if msb else "<")
    return stored, spacing, origin


def _is_identity_text(text: str) -> bool:
    try:
        values = [float(v) for v in text.split()]
    except ValueError:
        return False
    return len(values) == 9 and is_identity(np.array(values).reshape(3, 3))


class BrickRows:
    """A `MappedVolume`'s values with numpy slicing [z, y, x], as `write_pyramid` reads them:
    each read holds one row of bricks (`rows` samples of z and of y, every x), read through a
    memory map of that window alone and dropped with it. Why not one map of the whole file:
    every page a map has touched stays resident while it lives, so resident memory would grow
    to the whole volume."""

    def __init__(self, volume: MappedVolume, rows: int) -> None:
        self.volume = volume
        self.rows = rows
        self.shape = volume.shape
        self.dtype = volume.dtype
        #: NaN and Inf values met (each row counted once)
        self.nonfinite = 0
        self._row: tuple[tuple[int, int], NDArray] | None = None
        self._counted: set[tuple[int, int]] = set()

    def __getitem__(self, where: tuple[slice, slice, slice]) -> NDArray:
        z, y, x = (slice(*s.indices(n)[:2]) for s, n in zip(where, self.shape, strict=True))
        first = (z.start // self.rows * self.rows, y.start // self.rows * self.rows)
        inside = z.stop <= first[0] + self.rows and y.stop <= first[1] + self.rows
        if not inside:
            return self._read(z, y)[:, :, x]
        if self._row is None or self._row[0] != first:
            self._row = None
            release_free_heap()  # the last row's and its bricks' pages, else kept by a fragmented heap
            self._row = (
                first,
                self._read(slice(first[0], first[0] + self.rows), slice(first[1], first[1] + self.rows)),
            )
            self._count(first, self._row[1])
        values = self._row[1]
        return values[z.start - first[0] : z.stop - first[0], y.start - first[1] : y.stop - first[1], x]

    def _read(self, z: slice, y: slice) -> NDArray:
        """Samples z.start..z.stop, y.start..y.stop, every x, in the model's type."""
        volume = self.volume
        nz, ny, nx = volume.shape
        z0, z1 = max(z.start, 0), min(z.stop, nz)
        window = np.memmap(volume.data_file, dtype=volume.stored, mode="r", shape=(z1 - z0, ny, nx),
                           offset=volume.offset + z0 * ny * nx * volume.stored.itemsize)  # fmt: skip
        try:
            values = np.array(
                window[:, max(y.start, 0) : min(y.stop, ny), :], dtype=volume.stored.newbyteorder("=")
            )
        finally:
            del window  # unmapped: its pages leave this process
        return normalize_dtype(values, volume.name)[0]

    def _count(self, key: tuple[int, int], values: NDArray) -> None:
        if key in self._counted or not np.issubdtype(values.dtype, np.floating):
            return
        self._counted.add(key)
        self.nonfinite += int(values.size - np.count_nonzero(np.isfinite(values)))
