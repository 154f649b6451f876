"""Headerless raw volumes: the caller says what the bytes are (shape, dtype, byte order, geometry).

Read with numpy, not VTK: there is no header to trust, so the file size must match the shape
exactly, which catches most wrong guesses about shape or dtype.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import DTypeLike

from volren.errors import VolrenError, file_error
from volren.io.formats.base import Grid
from volren.io.limits import check_memory, product

_BYTE_ORDERS = {"little": "<", "big": ">", "native": "="}
_NUMPY_NAMES = (
    "uint8",
    "int8",
    "uint16",
    "int16",
    "uint32",
    "int32",
    "uint64",
    "int64",
    "float32",
    "float64",
)
#: The C, NRRD and MetaImage names people copy from headers, by their numpy name: C's 'float' and
#: 'int' have 4 bytes, where numpy alone would read 8.
_HEADER_NAMES = {
    "uchar": "uint8", "unsigned char": "uint8", "signed char": "int8", "char": "int8", "ushort": "uint16",
    "unsigned short": "uint16", "short": "int16", "uint": "uint32", "unsigned int": "uint32", "int": "int32",
    "ulonglong": "uint64", "longlong": "int64", "float": "float32", "double": "float64",
    "met_uchar": "uint8", "met_char": "int8", "met_ushort": "uint16", "met_short": "int16", "met_uint": "uint32",
    "met_int": "int32", "met_ulong": "uint32", "met_long": "int32", "met_ulong_long": "uint64",
    "met_long_long": "int64", "met_float": "float32", "met_double": "float64",
}  # fmt: skip
#: The type a cube of samples is guessed to have, by bytes per sample.
_GUESSED_TYPES = {1: "uint8", 2: "int16", 4: "float32", 8: "float64"}


def cube_guesses(n_bytes: int) -> list[tuple[int, str]]:
    """(side, dtype) of each cube of samples `n_bytes` could hold, one per sample size, sides of
    4 or more: what a headerless file's size suggests when nothing else is known."""
    guesses = []
    for size, name in _GUESSED_TYPES.items():
        side = round((n_bytes / size) ** (1 / 3)) if n_bytes % size == 0 else 0
        if side >= 4 and side**3 * size == n_bytes:
            guesses.append((side, name))
    return guesses


def headerless_problem(path: Path, flags: bool) -> str:
    """What to say of a file without a header: its size, the cube it may hold, and how to say
    what it holds (the command's flags, or `load_volume`'s arguments)."""
    n_bytes = path.stat().st_size
    guesses = cube_guesses(n_bytes)
    if not guesses:
        how = ("--raw-shape NX,NY,NZ (and --raw-dtype if it is not uint8, --raw-spacing, --raw-byte-order)" if flags
               else "shape=(nx, ny, nz) and dtype=")  # fmt: skip
        return f"headerless raw data ({n_bytes:,} bytes): give {how} to read it"
    (side, dtype), others = guesses[0], [f"{n}^3 {t}" for n, t in guesses[1:]]
    maybe = f"a {side}^3 {dtype} volume" + (f" (or {', '.join(others)})" if others else "")
    how = (f"--raw-shape {side},{side},{side} --raw-dtype {dtype} (and --raw-spacing, --raw-byte-order as needed)"
           if flags else f"shape=({side}, {side}, {side}), dtype={dtype!r}")  # fmt: skip
    return f"headerless raw data of {n_bytes:,} bytes: {maybe}? give {how}"


def parse_dtype(path: Path, dtype: DTypeLike) -> np.dtype:
    """A numpy dtype from numpy's names or a header's ('uchar', 'MET_SHORT', ...)."""
    name = " ".join(dtype.lower().split()) if isinstance(dtype, str) else dtype
    try:
        return np.dtype(_HEADER_NAMES.get(name, name) if isinstance(name, str) else name)
    except (TypeError, ValueError):
        raise file_error(
            path, f"unknown dtype {dtype!r}; give one of {', '.join(_NUMPY_NAMES)} (or a C, NRRD or MetaImage name "
            "such as uchar, short, float, MET_USHORT)"
        ) from None  # fmt: skip


#: Most samples along one axis: VTK's extents are 32-bit integers.
MAX_SIDE = 2**31 - 1


def _is_whole(n: object) -> bool:
    """An integer, or a float without a fraction (int() would drop one without a word)."""
    if isinstance(n, bool | np.bool_):
        return False
    return isinstance(n, int | np.integer) or (isinstance(n, float | np.floating) and float(n).is_integer())


def _shape(path: Path, shape: Sequence[int]) -> tuple[int, int, int]:
    try:
        items = list(shape)
    except TypeError:
        items = []
    if len(items) != 3 or not all(_is_whole(n) and 0 < n <= MAX_SIDE for n in items):
        shown = repr(shape) if len(repr(shape)) <= 60 else repr(shape)[:57] + "..."
        raise file_error(
            path, f"shape must be three whole numbers from 1 to {MAX_SIDE:,} (nx, ny, nz), got {shown}"
        )
    return tuple(int(n) for n in items)  # type: ignore[return-value]


def _dtype(path: Path, dtype: DTypeLike | None, byte_order: str, n_values: int, n_bytes: int) -> np.dtype:
    if not isinstance(byte_order, str) or byte_order not in _BYTE_ORDERS:
        raise file_error(path, f"byte_order must be one of {sorted(_BYTE_ORDERS)}, got {byte_order!r}")
    if dtype is None:
        if n_bytes == n_values:  # one byte per sample can only be uint8 (int8 must be asked for)
            return np.dtype(np.uint8)
        per = n_bytes / n_values
        raise file_error(
            path,
            f"headerless raw data needs dtype= (the file holds {n_bytes:,} bytes for {n_values:,} "
            f"samples, {per:g} each)",
        )
    dt = parse_dtype(path, dtype)
    if dt.kind not in "biuf":
        raise file_error(path, f"dtype must be a numeric type, got {dt}")
    return dt.newbyteorder(_BYTE_ORDERS[byte_order]) if dt.itemsize > 1 else dt


def raw_layout(
    path: Path, shape: Sequence[int], dtype: DTypeLike | None, byte_order: str, header_bytes: int
) -> tuple[tuple[int, int, int], np.dtype]:
    """(nx, ny, nz) and the stored dtype (byte order included) of headerless raw data, checked;
    whether the file holds them is `check_raw_size`'s."""
    nx, ny, nz = _shape(path, shape)
    if isinstance(header_bytes, bool) or not isinstance(header_bytes, int) or header_bytes < 0:
        raise file_error(path, f"header_bytes must be a non-negative integer, got {header_bytes!r}")
    dt = _dtype(path, dtype, byte_order, product((nx, ny, nz)), path.stat().st_size - header_bytes)
    return (nx, ny, nz), dt


def check_raw_size(path: Path, shape: tuple[int, int, int], dt: np.dtype, header_bytes: int) -> None:
    """Refuse a file that does not hold exactly the samples `shape` of `dt` after the header:
    without a header, the size is the one check on a guess of shape or dtype."""
    nx, ny, nz = shape
    expected = product(shape) * dt.itemsize
    have = path.stat().st_size - header_bytes
    if have != expected:
        raise file_error(
            path,
            f"dimensions do not match the data: shape {nx}x{ny}x{nz} of {dt.newbyteorder('=')} needs "
            f"{expected:,} bytes after a {header_bytes:,}-byte header, the file holds {have:,}",
        )


def load_raw(
    path: Path,
    shape: Sequence[int],
    dtype: DTypeLike | None = None,
    byte_order: str = "little",
    spacing: Sequence[float] = (1.0, 1.0, 1.0),
    origin: Sequence[float] = (0.0, 0.0, 0.0),
    header_bytes: int = 0,
) -> Grid:
    """values[k, j, i] from x-fastest samples after `header_bytes` bytes."""
    (nx, ny, nz), dt = raw_layout(path, shape, dtype, byte_order, header_bytes)
    n_values = product((nx, ny, nz))
    check_memory(path, f"shape {nx}x{ny}x{nz} {dt.newbyteorder('=')}", n_values * dt.itemsize)
    check_raw_size(path, (nx, ny, nz), dt, header_bytes)
    try:
        values = np.fromfile(path, dtype=dt, count=n_values, offset=header_bytes)
    except (OSError, ValueError) as exc:
        raise file_error(path, f"cannot read: {exc}") from None
    values = values.astype(dt.newbyteorder("="), copy=False).reshape(nz, ny, nx)
    try:
        sx, sy, sz = (float(v) for v in spacing)
        ox, oy, oz = (float(v) for v in origin)
    except (TypeError, ValueError, OverflowError):
        raise VolrenError(f"{path}: spacing and origin must be three numbers each") from None
    return Grid(values, (sx, sy, sz), (ox, oy, oz))
