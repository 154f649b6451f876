"""SLC volumes (.slc, the old VolVis format: a text header, an icon, then 8-bit slices, raw or
run-length encoded).

Read here with numpy, not with VTK: vtkSLCReader decodes the run-length slices with no bounds
checks (a run longer than the slice writes past the slice buffer, a run past the compressed size
reads past it), leaves the rest of a slice whose runs stop short uninitialized, trusts the icon
and compressed sizes (negative or huge ones included), and ignores the bits-per-voxel field. This
reader gives the same values and geometry as VTK's on valid files (values[k, j, i] = slice k,
row j, column i; origin 0; spacing from the header) and refuses everything else in one line that
names the slice at fault.

The layout, as vtkSLCReader reads it:

    11111  nx ny nz bits  sx sy sz  unit_type data_origin data_modification  compression
    icon_width icon_height X<three icon planes of width * height bytes>
    per slice: nx * ny raw bytes (compression 0), or `size X` then `size` bytes of runs
    (compression 1). A run byte c: c & 0x7f = n samples; c & 0x80: n literal bytes follow,
    else one byte repeated n times; n = 0 ends the slice.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from volren.errors import file_error
from volren.io.formats.base import FileFormat, Grid, Inspection, quote, read_head
from volren.io.formats.geometry import check_declared
from volren.io.limits import DataLayout, check_memory

_TOKEN = re.compile(rb"\s*(\S+)")
_ICON = re.compile(rb"\s*([-+]?\d+)\s+([-+]?\d+)\s*X")
_SLICE_SIZE = re.compile(rb"\s*([-+]?\d+)\s*X")
_HEADER_BYTES = 4096  # the 12 header words and the icon size fit in far less
ARRAY_NAME = "SLCImage"  # the name vtkSLCReader gives the values


def _words(path: Path, head: bytes) -> tuple[list[bytes], int]:
    """The 12 header words and the offset after them."""
    words, pos = [], 0
    for _ in range(12):
        m = _TOKEN.match(head, pos)
        if not m:
            break
        words.append(m.group(1))
        pos = m.end()
    if not words or words[0] != b"11111":
        raise file_error(path, "not an SLC file (it does not start with the magic number 11111)")
    if len(words) < 12:
        raise file_error(path, f"truncated: the SLC header has {len(words)} of its 12 words")
    return words, pos


def _int(path: Path, word: bytes, field: str) -> int:
    try:
        return int(word)
    except ValueError:
        raise file_error(path, f"malformed SLC header: {field} {quote(word)} must be an integer") from None


def inspect(path: Path) -> Inspection:
    head = read_head(path, _HEADER_BYTES)
    words, pos = _words(path, head)
    try:
        nx, ny, nz, bits = (int(w) for w in words[1:5])
    except ValueError:
        raise file_error(
            path, "malformed SLC header: expected 'nx ny nz bits' after the magic number"
        ) from None
    if min(nx, ny, nz) <= 0:
        raise file_error(path, f"malformed SLC header: size {nx}x{ny}x{nz}, {bits} bits per voxel")
    if bits != 8:
        raise file_error(path, f"SLC bits per voxel {bits}: only 8-bit SLC volumes exist (VolVis writes 8)")
    layout = DataLayout((nx, ny, nz), "uint8", nx * ny * nz)
    check_memory(path, layout.describe(), layout.memory_bytes)  # before anything else is parsed
    try:
        spacing = tuple(float(w) for w in words[5:8])
    except ValueError:
        shown = " ".join(w.decode("latin-1") for w in words[5:8])
        raise file_error(
            path, f"malformed SLC header: voxel spacing {quote(shown)} must be three numbers"
        ) from None
    facts = check_declared(path, spacing, None, "voxel spacing")  # type: ignore[arg-type]
    for word, field in zip(words[8:11], ("unit type", "data origin", "data modification")):
        _int(path, word, field)
    compression = _int(path, words[11], "compression flag")
    if compression not in (0, 1):
        raise file_error(
            path, f"unknown SLC compression flag {compression} (0: raw slices, 1: run-length encoded)"
        )
    m = _ICON.match(head, pos)
    if not m:
        raise file_error(
            path, "malformed SLC header: expected the icon size 'width height X' after the flags"
        )
    width, height = int(m.group(1)), int(m.group(2))
    if width < 0 or height < 0:
        raise file_error(path, f"malformed SLC header: icon size {width}x{height} is negative")
    icon_bytes = 3 * width * height
    data_start = m.end() + icon_bytes
    size = path.stat().st_size
    if data_start > size:
        raise file_error(
            path,
            f"truncated or bad icon size: the {width}x{height} icon (3 planes, {icon_bytes:,} bytes) "
            f"runs past the end of the file ({size - m.end():,} bytes follow its header)",
        )
    facts.update(shape=(nx, ny, nz), compression=compression, data_start=data_start)
    return Inspection("slc", path, layout, facts)


def _decode(path: Path, block: bytes, out: memoryview, plane: int, where: str) -> None:
    """One slice's runs into `out` (exactly `plane` bytes), every bound checked."""
    n, i, o = len(block), 0, 0
    while True:
        if i >= n:
            raise file_error(
                path,
                f"{where}: its {n:,} bytes of runs end without the end-of-slice marker (0) after "
                f"{o:,} of its {plane:,} samples",
            )
        c = block[i]
        i += 1
        count = c & 0x7F
        if count == 0:
            break
        if o + count > plane:
            raise file_error(
                path,
                f"{where}: a run of {count} samples at sample {o:,} goes past the slice's {plane:,} samples",
            )
        if c & 0x80:
            if i + count > n:
                raise file_error(
                    path,
                    f"{where}: a run of {count} literal bytes at byte {i - 1:,} goes past the slice's "
                    f"compressed size ({n:,} bytes)",
                )
            out[o : o + count] = block[i : i + count]
            i += count
        else:
            if i >= n:
                raise file_error(
                    path,
                    f"{where}: a repeated run at byte {i - 1:,} has no value byte before the slice's "
                    f"compressed size ({n:,} bytes) ends",
                )
            out[o : o + count] = block[i : i + 1] * count
            i += 1
        o += count
    if o != plane:
        raise file_error(path, f"{where}: its runs decode to {o:,} samples, the slice has {plane:,}")
    if i != n:
        raise file_error(
            path,
            f"{where}: {n - i:,} bytes follow the end-of-slice marker inside its compressed size of {n:,}",
        )


def read(path: Path, inspection: Inspection) -> Grid:
    """values[k, j, i] (uint8) from the slices, raw or run-length decoded."""
    facts = inspection.facts
    nx, ny, nz = facts["shape"]
    plane = nx * ny
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise file_error(path, f"cannot read: {exc.strerror or exc}") from None
    pos = facts["data_start"]
    notes: list[str] = []
    if facts["compression"] == 0:
        have = len(data) - pos
        if have < plane * nz:
            k = have // plane
            raise file_error(
                path,
                f"truncated: raw slice {k + 1} of {nz} holds {have - k * plane:,} of its {nx}x{ny} = "
                f"{plane:,} bytes (the header declares {nz} raw slices, compression flag 0)",
            )
        if have > plane * nz:
            raise file_error(
                path,
                f"{have - plane * nz:,} bytes follow the last of the {nz} raw {nx}x{ny} slices: wrong "
                "dimensions, or run-length encoded slices under compression flag 0",
            )
        values = np.frombuffer(data, np.uint8, plane * nz, pos).reshape(nz, ny, nx).copy()
    else:
        out = bytearray(plane * nz)
        for k in range(nz):
            where = f"slice {k + 1} of {nz} ({nx}x{ny})"
            m = _SLICE_SIZE.match(data, pos)
            if not m:
                if pos >= len(data) or not data[pos:].strip():
                    raise file_error(
                        path, f"truncated: {where} is missing (the file ends at byte {len(data):,})"
                    )
                raise file_error(
                    path,
                    f"{where}: no compressed size ('<bytes> X') where the slice starts at byte {pos:,}, "
                    f"found {quote(data[pos : pos + 12])} (raw slices under compression flag 1?)",
                )
            size = int(m.group(1))
            pos = m.end()
            if size < 0:
                raise file_error(path, f"{where}: compressed size {size} is negative")
            if pos + size > len(data):
                raise file_error(
                    path,
                    f"truncated or bad size: {where} declares {size:,} compressed bytes, only "
                    f"{len(data) - pos:,} follow",
                )
            _decode(path, data[pos : pos + size], memoryview(out)[k * plane : (k + 1) * plane], plane, where)
            pos += size
        if pos < len(data):
            notes.append(f"{path.name}: ignored {len(data) - pos:,} bytes after the last SLC slice")
        values = np.frombuffer(out, np.uint8).reshape(nz, ny, nx)
    spacing = facts.get("declared_spacing", (1.0, 1.0, 1.0))
    return Grid(values, spacing, (0.0, 0.0, 0.0), notes=notes)


SLC = FileFormat("SLC", (".slc",), inspect, read=read, array_name=ARRAY_NAME)
