"""NIfTI-1 and NIfTI-2 (.nii, .nii.gz).

VTK's NIfTI reader aborts the process (std::bad_alloc) on absurd dimensions, puts the image origin
at zero and the real placement into separate qform/sform matrices, and leaves the scl_slope /
scl_inter value scaling to the caller. It also takes, without a word, a bitpix that contradicts
the datatype, a zero pixdim, a vox_offset inside the header, the two-file magic 'ni1' in a .nii,
NaN in the geometry fields and a .nii.gz cut short. So every field it uses is checked here first:
magic, dim, datatype and bitpix agreeing, pixdim of the spatial axes finite and non-zero,
scl_slope/scl_inter, quatern/qoffset and srow finite (whichever of qform/sform is in use: a
non-finite number is never a valid header value), vox_offset a whole number past the header, and
all the data there (a .nii.gz is decompressed once to its end to count it and check its CRC). The
origin and the scaling are applied after reading.
"""

from __future__ import annotations

import gzip
import math
import struct
import zlib
from pathlib import Path

import numpy as np

from volren.errors import file_error
from volren.io._pv import ReadResult
from volren.io.formats.base import FileFormat, Grid, Inspection, quote
from volren.io.limits import DataLayout, check_memory, product

_DATATYPES = {
    2: "uint8", 4: "int16", 8: "int32", 16: "float32", 32: "complex64", 64: "float64",
    128: "rgb24", 256: "int8", 512: "uint16", 768: "uint32", 1024: "int64", 1280: "uint64",
    1536: "float128", 1792: "complex128", 2048: "complex256", 2304: "rgba32",
}  # fmt: skip
_BITS = {
    2: 8, 4: 16, 8: 32, 16: 32, 32: 64, 64: 64, 128: 24, 256: 8, 512: 16, 768: 32, 1024: 64, 1280: 64,
    1536: 128, 1792: 128, 2048: 256, 2304: 32,
}  # fmt: skip

# Where the fields are: NIfTI-1 (348-byte header) and NIfTI-2 (540 bytes); (offset, format code).
_LAYOUT = {
    348: {"datatype": (70, "h"), "bitpix": (72, "h"), "dim": (40, "8h"), "pixdim": (76, "8f"),
          "vox_offset": (108, "f"), "scl": (112, "2f"), "codes": (252, "2h"), "quatern": (256, "6f"),
          "srow": (280, "12f"), "magic": (344, 4)},
    540: {"datatype": (12, "h"), "bitpix": (14, "h"), "dim": (16, "8q"), "pixdim": (104, "8d"),
          "vox_offset": (168, "q"), "scl": (176, "2d"), "codes": (344, "2i"), "quatern": (352, "6d"),
          "srow": (400, "12d"), "magic": (4, 4)},
}  # fmt: skip
_QUATERN = ("quatern_b", "quatern_c", "quatern_d", "qoffset_x", "qoffset_y", "qoffset_z")
_SROW = tuple(f"srow_{axis}[{i}]" for axis in "xyz" for i in range(4))
_CHUNK = 1 << 20


def _read_header(path: Path) -> bytes:
    try:
        if path.name.lower().endswith(".gz"):
            with gzip.open(path, "rb") as f:
                return f.read(544)
        with open(path, "rb") as f:
            return f.read(544)
    except EOFError:
        raise file_error(path, "truncated: its gzip stream ends inside the NIfTI header") from None
    except (OSError, zlib.error) as exc:
        raise file_error(path, f"not a gzip-compressed NIfTI file ({exc})") from None


def _gzip_length(path: Path) -> int:
    """The uncompressed length of a .nii.gz, decompressing the whole stream in bounded pieces
    (zlib checks each member's end marker, CRC and length)."""
    total, fed = 0, False
    inflater = zlib.decompressobj(16 + zlib.MAX_WBITS)
    try:
        with open(path, "rb") as f:
            while data := f.read(_CHUNK):
                while data:
                    total += len(inflater.decompress(data, 16 * _CHUNK))
                    fed = True
                    data = inflater.unconsumed_tail
                    if inflater.eof:  # this member is complete: another may follow
                        data = inflater.unused_data
                        inflater, fed = zlib.decompressobj(16 + zlib.MAX_WBITS), False
                        if len(data) >= 2 and not data.startswith(b"\x1f\x8b"):
                            raise file_error(
                                path, "corrupt: bytes that are not gzip data follow its gzip stream"
                            )
    except zlib.error as exc:
        raise file_error(path, f"corrupt: its gzip stream cannot be decompressed ({exc})") from None
    except OSError as exc:
        raise file_error(path, f"cannot read: {exc.strerror or exc}") from None
    if fed and not inflater.eof:
        raise file_error(
            path, f"truncated: its gzip stream ends before its end marker, after {total:,} uncompressed bytes"
        )
    return total


def _finite(path: Path, names: tuple[str, ...], values: tuple[float, ...]) -> None:
    for name, value in zip(names, values):
        if not math.isfinite(value):
            raise file_error(path, f"NIfTI header field {name} is {value:g}; it must be a finite number")


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
    if sizeof_hdr == 540 and len(head) < 540:
        raise file_error(path, "truncated: shorter than a NIfTI-2 header (540 bytes)")
    layout = _LAYOUT[sizeof_hdr]

    def field(name: str) -> tuple:
        offset, fmt = layout[name]
        return struct.unpack_from(order + fmt, head, offset)  # type: ignore[arg-type]

    version = 1 if sizeof_hdr == 348 else 2
    offset, size = layout["magic"]
    magic = head[offset : offset + size]  # type: ignore[operator]
    if magic != f"n+{version}\0".encode():
        if magic == f"ni{version}\0".encode():
            raise file_error(
                path,
                f"NIfTI magic 'ni{version}' says the data is in a separate .img file; a .nii file "
                f"holds its data itself (magic 'n+{version}')",
            )
        raise file_error(path, f"not a NIfTI-{version} file: magic {quote(magic)} is not 'n+{version}'")
    dim = field("dim")
    (datatype,), (bitpix,) = field("datatype"), field("bitpix")
    ndim = dim[0]
    if not 1 <= ndim <= 7 or min(dim[1 : ndim + 1]) <= 0:
        raise file_error(path, f"malformed NIfTI header: dim = {list(dim)}")
    if datatype not in _DATATYPES or bitpix <= 0:
        raise file_error(path, f"unsupported NIfTI datatype {datatype} ({bitpix} bits per voxel)")
    if bitpix != _BITS[datatype]:
        raise file_error(
            path,
            f"NIfTI bitpix {bitpix} does not match datatype {datatype} ({_DATATYPES[datatype]}, "
            f"{_BITS[datatype]} bits per voxel)",
        )
    pixdim = field("pixdim")
    _finite(path, tuple(f"pixdim[{i}]" for i in range(min(ndim, 3) + 1)), pixdim[: min(ndim, 3) + 1])
    for i in range(1, min(ndim, 3) + 1):
        if pixdim[i] == 0:
            raise file_error(
                path, f"NIfTI pixdim[{i}] is 0: the voxel spacing along axis {i} must not be zero"
            )
    _finite(path, ("scl_slope", "scl_inter"), field("scl"))
    _finite(path, _QUATERN, field("quatern"))
    _finite(path, _SROW, field("srow"))
    (vox_offset,) = field("vox_offset")
    if not math.isfinite(vox_offset) or vox_offset != int(vox_offset):
        raise file_error(path, f"NIfTI vox_offset {vox_offset:g} must be a whole number of bytes")
    vox_offset = int(vox_offset)
    if vox_offset < sizeof_hdr + 4:
        raise file_error(
            path,
            f"NIfTI vox_offset {vox_offset} lies inside the header: the data of a .nii file starts "
            f"at byte {sizeof_hdr + 4} or later",
        )
    shape = tuple(int(d) for d in dim[1 : ndim + 1])
    nbytes = product(shape) * bitpix // 8
    if not path.name.lower().endswith(".gz"):
        return Inspection(
            "nifti", path, DataLayout(shape, _DATATYPES[datatype], nbytes, path, vox_offset, nbytes)
        )
    layout_gz = DataLayout(shape, _DATATYPES[datatype], nbytes)
    check_memory(path, layout_gz.describe(), nbytes)
    have = _gzip_length(path) - vox_offset
    if have < nbytes:
        raise file_error(
            path,
            f"truncated (or wrong dimensions): the header declares {layout_gz.describe()} = {nbytes:,} "
            f"bytes of data but only {max(have, 0):,} bytes follow (uncompressed)",
        )
    return Inspection("nifti", path, layout_gz)


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
    if slope != 0.0 and (slope != 1.0 or intercept != 0.0):  # scl_slope 0 means: no scaling
        values = grid.values
        finite = values[np.isfinite(values)] if values.dtype.kind == "f" else values
        ends = [slope * float(v) + intercept for v in (finite.min(), finite.max())] if finite.size else [0.0]
        if not all(np.isfinite(ends)):
            raise file_error(
                inspection.target,
                f"NIfTI scl_slope {slope:g} and scl_inter {intercept:g} take its values past the largest float",
            )
        wide = values.dtype == np.float64 or max(abs(e) for e in ends) >= 1e37 or abs(slope) < 1e-30
        target = np.float64 if wide else np.float32
        grid.values = values.astype(target) * target(slope) + target(intercept)
        grid.info.append(
            f"applied the NIfTI value scaling v * {slope:g} + {intercept:g} (as {np.dtype(target)})"
        )
    return grid


NIFTI = FileFormat("NIfTI", (".nii", ".nii.gz"), inspect, adjust=adjust)
