"""NIfTI-1 and NIfTI-2 (.nii, .nii.gz).

VTK's NIfTI reader aborts the process (std::bad_alloc) on absurd dimensions, puts the image origin
at zero and the real placement into separate qform/sform matrices, and leaves the scl_slope /
scl_inter value scaling to the caller. The header is checked here; the origin and the scaling are
applied after reading.
"""

from __future__ import annotations

import gzip
import struct
import zlib
from pathlib import Path

import numpy as np

from volren.errors import file_error
from volren.io._pv import ReadResult
from volren.io.formats.base import FileFormat, Grid, Inspection
from volren.io.limits import DataLayout, product

_DATATYPES = {
    2: "uint8", 4: "int16", 8: "int32", 16: "float32", 32: "complex64", 64: "float64",
    128: "rgb24", 256: "int8", 512: "uint16", 768: "uint32", 1024: "int64", 1280: "uint64",
    1536: "float128", 1792: "complex128", 2048: "complex256", 2304: "rgba32",
}  # fmt: skip


def _read_header(path: Path) -> bytes:
    try:
        if path.name.lower().endswith(".gz"):
            with gzip.open(path, "rb") as f:
                return f.read(544)
        with open(path, "rb") as f:
            return f.read(544)
    except (OSError, EOFError, zlib.error) as exc:
        raise file_error(path, f"not a gzip-compressed NIfTI file ({exc})") from None


def inspect(path: Path) -> Inspection:
    head = _read_header(path)
    if len(head) < 348:
        raise file_error(
            path, f"truncated or not a NIfTI file: {len(head)} bytes, less than a NIfTI header (348)"
        )
    for order in "<>":
        (sizeof_hdr,) = struct.unpack_from(order + "i", head, 0)
        if sizeof_hdr in (348, 540):
            break
    else:
        raise file_error(path, "not a NIfTI file (its first four bytes are not the header size 348 or 540)")
    if sizeof_hdr == 348:
        dim = struct.unpack_from(order + "8h", head, 40)
        datatype, bitpix = struct.unpack_from(order + "2h", head, 70)
        vox_offset = int(struct.unpack_from(order + "f", head, 108)[0])
        magic = head[344:348]
    else:
        if len(head) < 540:
            raise file_error(path, "truncated: shorter than a NIfTI-2 header (540 bytes)")
        magic = head[4:8]
        datatype, bitpix = struct.unpack_from(order + "2h", head, 12)
        dim = struct.unpack_from(order + "8q", head, 16)
        vox_offset = int(struct.unpack_from(order + "q", head, 168)[0])
    ndim = dim[0]
    if not 1 <= ndim <= 7 or min(dim[1 : ndim + 1]) <= 0:
        raise file_error(path, f"malformed NIfTI header: dim = {list(dim)}")
    if datatype not in _DATATYPES or bitpix <= 0:
        raise file_error(path, f"unsupported NIfTI datatype {datatype} ({bitpix} bits per voxel)")
    shape = tuple(int(d) for d in dim[1 : ndim + 1])
    nbytes = product(shape) * bitpix // 8
    layout = DataLayout(shape, _DATATYPES[datatype], nbytes)
    single_file = magic in (b"n+1\x00", b"n+2\x00")
    if single_file and not path.name.lower().endswith(".gz"):
        layout = DataLayout(shape, _DATATYPES[datatype], nbytes, path, vox_offset, nbytes)
    return Inspection("nifti", path, layout)


def adjust(grid: Grid, result: ReadResult, inspection: Inspection) -> Grid:
    """Origin (and direction, to be reported) from the qform, else the sform; apply scl_slope/inter."""
    matrix = result.info.get("qform")
    if matrix is None:
        matrix = result.info.get("sform")
    if matrix is not None:
        linear = matrix[:3, :3]
        norms = np.linalg.norm(linear, axis=0)
        linear = linear / np.where(norms == 0, 1, norms)
        grid.origin = tuple(float(v) for v in matrix[:3, 3])  # type: ignore[assignment]
        grid.direction = linear
    slope, intercept = result.info.get("slope", 1.0), result.info.get("intercept", 0.0)
    if slope not in (0.0, 1.0) or intercept != 0.0:
        target = np.float64 if grid.values.dtype == np.float64 else np.float32
        grid.values = grid.values.astype(target) * target(slope) + target(intercept)
        grid.info.append(
            f"applied the NIfTI value scaling v * {slope:g} + {intercept:g} (as {np.dtype(target)})"
        )
    return grid


NIFTI = FileFormat("NIfTI", (".nii", ".nii.gz"), inspect, adjust=adjust)
