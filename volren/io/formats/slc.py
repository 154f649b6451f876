"""SLC volumes (.slc, the old VolVis format: a text header, an icon, then RLE-compressed slices).

VTK's SLC reader aborts the process (std::bad_alloc) on absurd dimensions and returns a full-size
volume after reporting a short slice; the header is checked here, truncation is left to the
reader's own report (the slices are compressed, so their size is unknown in advance).
"""

from __future__ import annotations

from pathlib import Path

from volren.errors import file_error
from volren.io.formats.base import FileFormat, Inspection, read_head
from volren.io.limits import DataLayout, product


def inspect(path: Path) -> Inspection:
    words = read_head(path, 512).split()
    if not words or words[0] != b"11111":
        raise file_error(path, "not an SLC file (it does not start with the magic number 11111)")
    try:
        nx, ny, nz, bits = (int(w) for w in words[1:5])
    except ValueError:
        raise file_error(
            path, "malformed SLC header: expected 'nx ny nz bits' after the magic number"
        ) from None
    if min(nx, ny, nz) <= 0 or bits not in (8, 16):
        raise file_error(path, f"malformed SLC header: size {nx}x{ny}x{nz}, {bits} bits per voxel")
    shape = (nx, ny, nz)
    return Inspection("slc", path, DataLayout(shape, f"{bits}-bit", product(shape) * bits // 8))


SLC = FileFormat("SLC", (".slc",), inspect)
