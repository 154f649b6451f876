"""DICOM series: a folder of slice files (or one of its files, meaning the folder).

Quirks of vtkDICOMImageReader (VTK 9.7), measured on series written by volren/testing/dicom_series.py:
- it flips the rows (DICOM's first row comes out last) and orders slices by *decreasing*
  position along the slice normal, while its ImagePositionPatient is that of the lowest slice and
  its output origin is (0, 0, 0). Undoing both flips puts the values back in patient order,
  values[k, j, i] = slice k (increasing position), row j, column i, with the origin at the
  first slice's ImagePositionPatient: what the file means.
- it applies RescaleSlope/Intercept itself, keeping the stored integer type.
- a truncated slice file is read without any message (the missing pixels are garbage), and
  files that are not DICOM are skipped silently; so every slice is checked here first.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from volren.errors import file_error
from volren.io._pv import ReadResult
from volren.io.formats.base import FileFormat, Grid, Inspection, read_head
from volren.io.limits import DataLayout

_PIXEL_DATA = b"\xe0\x7f\x10\x00"
_UNDEFINED = 0xFFFFFFFF


def has_dicom_magic(path: Path) -> bool:
    try:
        return read_head(path, 132)[128:132] == b"DICM"
    except OSError:
        return False


def _candidates(folder: Path) -> list[Path]:
    return sorted(
        p for p in folder.iterdir() if p.is_file() and (p.suffix.lower() == ".dcm" or has_dicom_magic(p))
    )


def _us(data: bytes, group: int, element: int) -> int | None:
    """An unsigned-short element, explicit or implicit VR little endian, found by its tag bytes."""
    tag = struct.pack("<HH", group, element)
    for prefix in (tag + b"US\x02\x00", tag + b"\x02\x00\x00\x00"):
        i = data.find(prefix)
        if i >= 0 and i + len(prefix) + 2 <= len(data):
            return struct.unpack_from("<H", data, i + len(prefix))[0]
    return None


def _pixel_data_ok(data: bytes, size: int, expected: int) -> bool | None:
    """Whether a pixel-data element of `expected` bytes fits in the file (None: cannot tell)."""
    start = 0
    while (i := data.find(_PIXEL_DATA, start)) >= 0:
        start = i + 1
        if data[i + 4 : i + 6] in (b"OB", b"OW", b"OF", b"UN") and data[i + 6 : i + 8] == b"\0\0":
            length_at, payload = i + 8, i + 12
        else:
            length_at, payload = i + 4, i + 8
        if length_at + 4 > len(data):
            continue
        (length,) = struct.unpack_from("<I", data, length_at)
        if length == _UNDEFINED:
            return None  # encapsulated (compressed) pixels: sizes unknown
        if length == expected:
            return payload + length <= size
    return None if size >= expected else False


def inspect(path: Path) -> Inspection:
    folder = path if path.is_dir() else path.parent
    slices = []
    for file in _candidates(folder):
        head = read_head(file, 1 << 18)
        rows, cols = _us(head, 0x0028, 0x0010), _us(head, 0x0028, 0x0011)
        if not rows or not cols:
            continue  # not an image (DICOMDIR, reports, ...): VTK skips these too
        bits = _us(head, 0x0028, 0x0100) or 16
        samples = _us(head, 0x0028, 0x0002) or 1
        slices.append((file, rows, cols, samples * ((bits + 7) // 8), head))
    if not slices:
        raise file_error(path, "holds no DICOM images (looked for .dcm files and files with a DICM header)")
    file0, rows0, cols0, item0, _ = slices[0]
    for file, rows, cols, item, head in slices:
        if (rows, cols, item) != (rows0, cols0, item0):
            raise file_error(
                path,
                f"the slices differ in size: {file0.name} is {cols0}x{rows0}, {item0} bytes per pixel, "
                f"{file.name} is {cols}x{rows}, {item} bytes per pixel",
            )
        size = file.stat().st_size
        ok = _pixel_data_ok(head, size, rows * cols * item)
        if ok is None and size > len(head):  # pixel data beyond the first read: look at it all
            ok = _pixel_data_ok(file.read_bytes(), size, rows * cols * item)
        if ok is False:
            raise file_error(
                path, f"truncated: slice {file.name} holds fewer pixel bytes than its header declares"
            )
    shape = (cols0, rows0, len(slices))
    nbytes = cols0 * rows0 * len(slices) * item0
    return Inspection("dicom", folder, DataLayout(shape, f"{item0}-byte", nbytes), {"slices": len(slices)})


def adjust(grid: Grid, result: ReadResult, inspection: Inspection) -> Grid:
    """Undo VTK's row and slice flips; place the grid at the first slice's ImagePositionPatient."""
    grid.values = np.ascontiguousarray(grid.values[::-1, ::-1, :])
    grid.origin = result.info.get("position", grid.origin)
    orientation = result.info.get("orientation")
    if orientation and len(orientation) == 6 and any(orientation):
        row, col = np.array(orientation[:3]), np.array(orientation[3:])
        grid.direction = np.column_stack([row, col, np.cross(row, col)])
    n_read, n_found = grid.values.shape[0], inspection.facts.get("slices", 0)
    if n_read != n_found:
        grid.notes.append(
            f"read {n_read} of the {n_found} DICOM images in the folder (more than one series?)"
        )
    return grid


DICOM = FileFormat("DICOM series", (".dcm",), inspect, adjust=adjust)
