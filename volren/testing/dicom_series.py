"""A minimal DICOM series writer for tests and the fuzz corpus (VTK reads DICOM but cannot write it).

Each slice is a CT image in explicit VR little endian with just the elements volren's DICOM reader
uses: sizes, pixel format, spacing, position, orientation, rescale, then signed 16-bit pixels.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

_LONG_VRS = ("OB", "OW", "OF", "SQ", "UT", "UN")
CT_IMAGE = "1.2.840.10008.5.1.4.1.1.2"
EXPLICIT_LITTLE = "1.2.840.10008.1.2.1"


def element(group: int, elem: int, vr: str, value: str | bytes) -> bytes:
    if isinstance(value, str):
        value = value.encode("ascii")
        if len(value) % 2:
            value += b"\0" if vr == "UI" else b" "
    if len(value) % 2:
        value += b"\0"
    head = struct.pack("<HH", group, elem) + vr.encode("ascii")
    if vr in _LONG_VRS:
        return head + b"\0\0" + struct.pack("<I", len(value)) + value
    return head + struct.pack("<H", len(value)) + value


def _us(v: int) -> bytes:
    return struct.pack("<H", v)


def slice_bytes(
    pixels: NDArray,
    index: int,
    spacing: tuple[float, float, float],
    position: tuple[float, float, float],
    slope: float = 1.0,
    intercept: float = 0.0,
) -> bytes:
    """One slice file: `pixels` is (rows, columns) int16, row 0 at the top of the image."""
    rows, cols = pixels.shape
    sop = f"1.2.826.0.1.3680043.2.1125.{index + 1}"
    meta = (
        element(2, 1, "OB", b"\0\1")
        + element(2, 2, "UI", CT_IMAGE)
        + element(2, 3, "UI", sop)
        + element(2, 0x10, "UI", EXPLICIT_LITTLE)
    )
    meta = element(2, 0, "UL", struct.pack("<I", len(meta))) + meta
    x, y, z = position
    data = b"".join([
        element(0x08, 0x16, "UI", CT_IMAGE), element(0x08, 0x18, "UI", sop), element(0x08, 0x60, "CS", "CT"),
        element(0x10, 0x10, "PN", "Test^Volren"), element(0x18, 0x50, "DS", f"{spacing[2]:g}"),
        element(0x20, 0x0D, "UI", "1.2.826.0.1.3680043.2.1125.1"),
        element(0x20, 0x0E, "UI", "1.2.826.0.1.3680043.2.1125.2"),
        element(0x20, 0x13, "IS", str(index + 1)),
        element(0x20, 0x32, "DS", f"{x:g}\\{y:g}\\{z:g}"), element(0x20, 0x37, "DS", "1\\0\\0\\0\\1\\0"),
        element(0x28, 0x02, "US", _us(1)), element(0x28, 0x04, "CS", "MONOCHROME2"),
        element(0x28, 0x10, "US", _us(rows)), element(0x28, 0x11, "US", _us(cols)),
        element(0x28, 0x30, "DS", f"{spacing[1]:g}\\{spacing[0]:g}"),  # row spacing (y), column spacing (x)
        element(0x28, 0x100, "US", _us(16)), element(0x28, 0x101, "US", _us(16)),
        element(0x28, 0x102, "US", _us(15)), element(0x28, 0x103, "US", _us(1)),
        element(0x28, 0x1052, "DS", f"{intercept:g}"), element(0x28, 0x1053, "DS", f"{slope:g}"),
        element(0x7FE0, 0x10, "OW", np.ascontiguousarray(pixels, dtype="<i2").tobytes()),
    ])  # fmt: skip
    return b"\0" * 128 + b"DICM" + meta + data


def write_series(
    folder: Path,
    values: NDArray,
    spacing: tuple[float, float, float],
    origin: tuple[float, float, float],
    step: float | None = None,
) -> list[Path]:
    """values[k, j, i] as slices k = 0.. at origin + k * step along z (step defaults to spacing z)."""
    folder.mkdir(parents=True, exist_ok=True)
    step = spacing[2] if step is None else step
    paths = []
    for k, pixels in enumerate(values):
        path = folder / f"slice{k:03d}.dcm"
        path.write_bytes(slice_bytes(pixels, k, spacing, (origin[0], origin[1], origin[2] + k * step)))
        paths.append(path)
    return paths
