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


def _shape(path: Path, shape: Sequence[int]) -> tuple[int, int, int]:
    try:
        dims = tuple(int(n) for n in shape)
    except (TypeError, ValueError):
        raise file_error(path, f"shape must be three integers (nx, ny, nz), got {shape!r}") from None
    if len(dims) != 3 or min(dims) <= 0:
        raise file_error(path, f"shape must be three positive integers (nx, ny, nz), got {shape!r}")
    return dims  # type: ignore[return-value]


def _dtype(path: Path, dtype: DTypeLike | None, byte_order: str, n_values: int, n_bytes: int) -> np.dtype:
    if byte_order not in _BYTE_ORDERS:
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
    try:
        dt = np.dtype(dtype)
    except TypeError:
        raise file_error(path, f"unknown dtype {dtype!r}") from None
    if dt.kind not in "biuf":
        raise file_error(path, f"dtype must be a numeric type, got {dt}")
    return dt.newbyteorder(_BYTE_ORDERS[byte_order]) if dt.itemsize > 1 else dt


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
    nx, ny, nz = _shape(path, shape)
    if not isinstance(header_bytes, int) or header_bytes < 0:
        raise file_error(path, f"header_bytes must be a non-negative integer, got {header_bytes!r}")
    n_values = product((nx, ny, nz))
    size = path.stat().st_size
    dt = _dtype(path, dtype, byte_order, n_values, size - header_bytes)
    expected = n_values * dt.itemsize
    check_memory(path, f"shape {nx}x{ny}x{nz} {dt.newbyteorder('=')}", expected)
    if size - header_bytes != expected:
        raise file_error(
            path,
            f"dimensions do not match the data: shape {nx}x{ny}x{nz} of {dt.newbyteorder('=')} needs "
            f"{expected:,} bytes after a {header_bytes:,}-byte header, the file holds "
            f"{size - header_bytes:,}",
        )
    try:
        values = np.fromfile(path, dtype=dt, count=n_values, offset=header_bytes)
    except (OSError, ValueError) as exc:
        raise file_error(path, f"cannot read: {exc}") from None
    values = values.astype(dt.newbyteorder("="), copy=False).reshape(nz, ny, nx)
    try:
        sx, sy, sz = (float(v) for v in spacing)
        ox, oy, oz = (float(v) for v in origin)
    except (TypeError, ValueError):
        raise VolrenError(f"{path}: spacing and origin must be three numbers each") from None
    return Grid(values, (sx, sy, sz), (ox, oy, oz))
