"""DICOM series: a folder of slice files (or one of its files, meaning its series in that folder).

Read with pydicom and numpy, not with vtkDICOMImageReader: that reader (VTK 9.7) takes a pixel
element that is too short, too long or missing without a word (the rest of the slice is
uninitialized memory), skips slice files it cannot parse, stacks two slices at the same position,
reads 12-bit, 0-bit and 3-sample pixels as 16-bit grey, dies of an uncaught C++ exception
(SIGSEGV) on a decimal string outside float's range while parsing the header (RescaleSlope 1e39
or 1e-50), and overruns its output buffer (double free) when one slice's rescale is fractional
and another's is not: it sizes the volume from one slice's pixel type and copies each slice at
its own. It also takes the z spacing from SliceThickness, not from the slice positions.

Here pydicom parses each file's elements; the few values volren uses are decoded from their raw
bytes and checked, each error one line naming the slice file:

- Rows, Columns > 0; BitsAllocated 8 or 16; SamplesPerPixel 1; PixelRepresentation 0 or 1;
  BitsStored 1..BitsAllocated; one frame; an uncompressed transfer syntax;
- the pixel element holds exactly Rows * Columns * BitsAllocated / 8 bytes (plus the one pad
  byte of an odd length) and the file holds all of them;
- PixelSpacing two finite positive numbers, SliceThickness finite and positive, position three
  finite numbers, orientation six finite numbers making two perpendicular, non-zero directions,
  the same in every slice; no two slices at the same position;
- RescaleSlope (non-zero) and RescaleIntercept finite, and the rescaled values finite in float64.

values[k, j, i] = slice k in increasing position along the slice normal (row x column
direction), row j (the file's first row first), column i; the origin is the first slice's
ImagePositionPatient; the z spacing is the mean step between slice positions. Files that are
DICOM but hold no image (DICOMDIR, reports) are skipped and noted.
"""

from __future__ import annotations

import math
import struct
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from volren.errors import VolrenError, file_error
from volren.io.formats.base import FileFormat, Grid, Inspection, quote, read_head
from volren.io.limits import check_memory

ARRAY_NAME = "DICOMImage"  # the name vtkDICOMImageReader gave the values

_NATIVE = {
    "1.2.840.10008.1.2": "implicit VR little endian",
    "1.2.840.10008.1.2.1": "explicit VR little endian",
    "1.2.840.10008.1.2.1.99": "deflated explicit VR little endian",
    "1.2.840.10008.1.2.2": "explicit VR big endian",
}

_ROWS, _COLUMNS = 0x00280010, 0x00280011
_SAMPLES, _FRAMES = 0x00280002, 0x00280008
_BITS_ALLOCATED, _BITS_STORED, _PIXEL_REPRESENTATION = 0x00280100, 0x00280101, 0x00280103
_PIXEL_SPACING, _SLICE_THICKNESS = 0x00280030, 0x00180050
_POSITION, _ORIENTATION = 0x00200032, 0x00200037
_SLOPE, _INTERCEPT = 0x00281053, 0x00281052
_SERIES_UID, _INSTANCE_NUMBER, _SOP_CLASS = 0x0020000E, 0x00200013, 0x00080016
_PIXEL_DATA = 0x7FE00010
_UNDEFINED = 0xFFFFFFFF


def has_dicom_magic(path: Path) -> bool:
    try:
        return read_head(path, 132)[128:132] == b"DICM"
    except OSError:
        return False


def _candidates(folder: Path) -> list[Path]:
    try:
        entries = sorted(folder.iterdir())
    except OSError as exc:
        raise file_error(folder, f"cannot list the folder: {exc.strerror or exc}") from None
    return [p for p in entries if p.is_file() and (p.suffix.lower() == ".dcm" or has_dicom_magic(p))]


# --------------------------------------------------------------------------- one slice file


@dataclass
class _Slice:
    file: Path
    rows: int
    columns: int
    bits: int
    signed: bool
    little: bool
    pixels: bytes
    slope: float
    intercept: float
    pixel_spacing: tuple[float, float] | None  # (between rows = y, between columns = x)
    thickness: float | None
    position: tuple[float, float, float] | None
    orientation: tuple[float, ...] | None
    series: str
    instance: int | None

    def stored(self) -> np.ndarray:
        dtype = np.dtype(f"{'<' if self.little else '>'}{'i' if self.signed else 'u'}{self.bits // 8}")
        return np.frombuffer(self.pixels, dtype, self.rows * self.columns).reshape(self.rows, self.columns)

    def pixel_format(self) -> str:
        return f"{self.bits}-bit {'signed' if self.signed else 'unsigned'}"


class _Fields:
    """The raw values of one parsed file, decoded and checked here (pydicom only splits elements)."""

    def __init__(self, path: Path, file: Path, ds) -> None:  # noqa: ANN001 - a pydicom Dataset
        self.path, self.file, self.ds = path, file, ds

    def fail(self, problem: str) -> VolrenError:
        return file_error(self.path, f"slice {self.file.name}: {problem}")

    def raw(self, tag: int):  # noqa: ANN201 - RawDataElement | DataElement | None
        try:
            return self.ds.get_item(tag) if tag in self.ds else None
        except Exception as exc:  # pydicom decodes on access; anything it raises is this file's fault
            raise self.fail(
                f"element ({tag >> 16:04X},{tag & 0xFFFF:04X}) cannot be read ({_short(exc)})"
            ) from None

    def text(self, tag: int) -> str | None:
        elem = self.raw(tag)
        if elem is None or elem.value is None:
            return None
        value = elem.value
        if isinstance(value, bytes):
            value = value.decode("latin-1")
        elif not isinstance(value, str):  # already converted by pydicom (a number or a list of them)
            value = "\\".join(str(v) for v in value) if isinstance(value, (list, tuple)) else str(value)
        value = value.strip(" \0")
        return value or None

    def us(self, tag: int, name: str) -> int | None:
        elem = self.raw(tag)
        if elem is None or elem.value is None or elem.value == b"":
            return None
        value = elem.value
        if isinstance(value, int):
            return value
        if not isinstance(value, bytes) or len(value) != 2:
            raise self.fail(f"{name} must be one unsigned short (2 bytes), it holds {quote(repr(value))}")
        little = getattr(elem, "is_little_endian", True)
        return int(struct.unpack("<H" if little else ">H", value)[0])

    def numbers(self, tag: int, name: str, count: int) -> tuple[float, ...] | None:
        text = self.text(tag)
        if text is None:
            return None
        parts = [p.strip(" \0") for p in text.split("\\")]
        try:
            values = tuple(float(p) for p in parts)
        except ValueError:
            raise self.fail(
                f"{name} {quote(text)} must be {count} number{'s' if count > 1 else ''}"
            ) from None
        if len(values) != count:
            raise self.fail(f"{name} {quote(text)} must be {count} number{'s' if count > 1 else ''}")
        if not all(math.isfinite(v) for v in values):
            raise self.fail(f"{name} {quote(text)} must be finite")
        return values

    def integer(self, tag: int, name: str) -> int | None:
        text = self.text(tag)
        if text is None:
            return None
        try:
            return int(text)
        except ValueError:
            raise self.fail(f"{name} {quote(text)} must be an integer") from None


def _short(exc: BaseException) -> str:
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text[:120] + ("..." if len(text) > 120 else "")


def _dcmread(path: Path, file: Path):  # noqa: ANN202 - a pydicom Dataset
    import pydicom  # imported here: only DICOM needs it (about 0.1 s)

    try:
        return pydicom.dcmread(file, force=True)
    except MemoryError:
        raise file_error(
            path, f"slice {file.name}: an element declares more bytes than memory holds"
        ) from None
    except Exception as exc:  # pydicom's parse errors are of many types; every one is this file's fault
        raise file_error(path, f"slice {file.name}: not a readable DICOM file ({_short(exc)})") from None


def _sop_class(ds) -> str:  # noqa: ANN001
    for getter in (lambda: ds.file_meta.get("MediaStorageSOPClassUID"), lambda: ds.get("SOPClassUID")):
        try:
            uid = getter()
        except Exception:  # noqa: BLE001 - a garbled UID is no class
            uid = None
        if uid:
            return str(uid).strip(" \0")
    return ""


def _is_known_non_image(sop_class: str) -> bool:
    from pydicom.uid import UID

    name = UID(sop_class).name if sop_class else ""
    return bool(name) and name != sop_class and "Image" not in name


def _transfer_syntax(fields: _Fields) -> None:
    try:
        uid = fields.ds.file_meta.get("TransferSyntaxUID")
    except Exception:  # noqa: BLE001
        uid = None
    if uid is None:
        return  # no meta header: pydicom found the encoding from the elements themselves
    uid = str(uid).strip(" \0")
    if uid in _NATIVE:
        return
    from pydicom.uid import UID

    name = UID(uid).name
    if name != uid:
        raise fields.fail(
            f"compressed pixel data ({name}) is not supported; decompress the series first "
            "(e.g. gdcmconv --raw or dcmdjpeg)"
        )
    raise fields.fail(f"unknown transfer syntax {quote(uid)}")


def _parse(path: Path, file: Path, magic: bool) -> _Slice | None:
    """One slice file checked, or None for a DICOM file that is not an image (skipped)."""
    try:
        empty = file.stat().st_size == 0
    except OSError as exc:
        raise file_error(path, f"slice {file.name}: cannot read: {exc.strerror or exc}") from None
    if empty:
        raise file_error(path, f"slice {file.name}: empty file (0 bytes)")
    ds = _dcmread(path, file)
    f = _Fields(path, file, ds)
    _transfer_syntax(f)
    rows, columns = f.us(_ROWS, "Rows"), f.us(_COLUMNS, "Columns")
    has_pixels = _PIXEL_DATA in ds
    if rows is None and columns is None and not has_pixels:
        if magic and _is_known_non_image(_sop_class(ds)):
            return None
        raise f.fail("not a DICOM image (no Rows, Columns or Pixel Data: not DICOM, or truncated)")
    if not rows or not columns:
        raise f.fail(f"Rows {rows} and Columns {columns} must both be present and positive")
    if not has_pixels:
        raise f.fail(f"no pixel data after its {columns}x{rows} header (truncated?)")
    samples = f.us(_SAMPLES, "SamplesPerPixel")
    if samples is not None and samples != 1:
        raise f.fail(f"SamplesPerPixel {samples}: volren reads one sample per pixel (grey images) only")
    bits = f.us(_BITS_ALLOCATED, "BitsAllocated")
    if bits not in (8, 16):
        raise f.fail(f"BitsAllocated {bits}: volren reads 8- and 16-bit DICOM pixels only")
    stored = f.us(_BITS_STORED, "BitsStored")
    if stored is not None and not 1 <= stored <= bits:
        raise f.fail(f"BitsStored {stored} must be 1 to BitsAllocated ({bits})")
    representation = f.us(_PIXEL_REPRESENTATION, "PixelRepresentation")
    if representation not in (None, 0, 1):
        raise f.fail(f"PixelRepresentation {representation} must be 0 (unsigned) or 1 (signed)")
    frames = f.integer(_FRAMES, "NumberOfFrames")
    if frames is not None and frames != 1:
        raise f.fail(f"NumberOfFrames {frames}: volren reads single-frame slices only")
    pixels = f.raw(_PIXEL_DATA)
    value = pixels.value if pixels is not None else None
    if not isinstance(value, bytes):
        raise f.fail("pixel data cannot be read")
    declared = getattr(pixels, "length", len(value))
    expected = rows * columns * bits // 8
    if declared == _UNDEFINED:
        raise f.fail("encapsulated (compressed) pixel data under an uncompressed transfer syntax")
    if len(value) < declared:
        raise f.fail(
            f"truncated: its pixel element declares {declared:,} bytes, the file holds {len(value):,}"
        )
    if len(value) not in (expected, expected + (expected % 2)):
        raise f.fail(
            f"its pixel element holds {len(value):,} bytes, but Columns x Rows x BitsAllocated/8 = "
            f"{columns} x {rows} x {bits // 8} = {expected:,}"
        )
    slope = f.numbers(_SLOPE, "RescaleSlope", 1)
    intercept = f.numbers(_INTERCEPT, "RescaleIntercept", 1)
    if slope is not None and slope[0] == 0:
        raise f.fail("RescaleSlope 0 would make every value the intercept")
    spacing = f.numbers(_PIXEL_SPACING, "PixelSpacing", 2)
    if spacing is not None and min(spacing) <= 0:
        raise f.fail(f"PixelSpacing {spacing[0]:g}\\{spacing[1]:g} must be positive")
    thickness = f.numbers(_SLICE_THICKNESS, "SliceThickness", 1)
    if thickness is not None and thickness[0] <= 0:
        raise f.fail(f"SliceThickness {thickness[0]:g} must be positive")
    position = f.numbers(_POSITION, "ImagePositionPatient", 3)
    orientation = f.numbers(_ORIENTATION, "ImageOrientationPatient", 6)
    if orientation is not None:
        row, col = np.array(orientation[:3]), np.array(orientation[3:])
        if min(np.linalg.norm(row), np.linalg.norm(col)) < 1e-6:
            raise f.fail(f"ImageOrientationPatient {_shown(orientation)} has a zero direction")
        row, col = row / np.linalg.norm(row), col / np.linalg.norm(col)
        if abs(float(row @ col)) > 0.01:
            raise f.fail(
                f"ImageOrientationPatient {_shown(orientation)}: its row and column directions are not "
                "perpendicular"
            )
        orientation = (*row.tolist(), *col.tolist())
    return _Slice(
        file, rows, columns, bits, representation == 1, bool(getattr(pixels, "is_little_endian", True)),
        value[:expected], slope[0] if slope else 1.0, intercept[0] if intercept else 0.0,
        spacing, thickness[0] if thickness else None,  # type: ignore[arg-type]
        position, orientation, f.text(_SERIES_UID) or "", f.integer(_INSTANCE_NUMBER, "InstanceNumber"),
    )  # fmt: skip


def _shown(values) -> str:  # noqa: ANN001
    return "\\".join(f"{v:g}" for v in values)


# ------------------------------------------------------------------------------------ the series


def inspect(path: Path) -> Inspection:
    folder = path if path.is_dir() else path.parent
    return Inspection("dicom", folder, None, {"file": None if path.is_dir() else path})


def _one_series(path: Path, slices: list[_Slice], named: Path | None) -> list[_Slice]:
    groups: dict[str, list[_Slice]] = {}
    for s in slices:
        groups.setdefault(s.series, []).append(s)
    if len(groups) == 1:
        return slices
    if named is not None:
        for group in groups.values():
            if any(s.file.name == named.name for s in group):
                return group
    listed = ", ".join(
        f"{quote(uid or '(none)', 24)}: {len(g)} image{'s' if len(g) > 1 else ''} (e.g. {g[0].file.name})"
        for uid, g in list(groups.items())[:4]
    )
    raise file_error(
        path, f"holds {len(groups)} DICOM series ({listed}); name one slice file of the series to read"
    )


def _same_layout(path: Path, slices: list[_Slice]) -> None:
    first = slices[0]
    for s in slices[1:]:
        if (s.rows, s.columns) != (first.rows, first.columns):
            raise file_error(
                path,
                f"the slices differ in size: {first.file.name} is {first.columns}x{first.rows}, "
                f"{s.file.name} is {s.columns}x{s.rows}",
            )
        if (s.bits, s.signed) != (first.bits, first.signed):
            raise file_error(
                path,
                f"the slices differ in pixel format: {first.file.name} is {first.pixel_format()}, "
                f"{s.file.name} is {s.pixel_format()}",
            )
        if s.pixel_spacing != first.pixel_spacing:
            raise file_error(
                path,
                f"the slices differ in PixelSpacing: {first.file.name} has "
                f"{_shown(first.pixel_spacing or ())}, {s.file.name} has {_shown(s.pixel_spacing or ())}",
            )


def _geometry(path: Path, slices: list[_Slice], notes: list[str]):  # noqa: ANN202
    """(slices in patient order, z spacing, origin, direction)."""
    name = path.name
    with_position = [s for s in slices if s.position is not None]
    with_orientation = [s for s in slices if s.orientation is not None]
    for having, what in (
        (with_position, "ImagePositionPatient"),
        (with_orientation, "ImageOrientationPatient"),
    ):
        if having and len(having) != len(slices):
            lacking = next(s for s in slices if all(s is not h for h in having))
            raise file_error(
                path, f"slice {lacking.file.name} has no {what}, while {having[0].file.name} has one"
            )
    for s in with_orientation[1:]:
        if np.abs(np.subtract(s.orientation, with_orientation[0].orientation)).max() > 1e-4:  # type: ignore[arg-type]
            raise file_error(
                path,
                f"the slices are not parallel: ImageOrientationPatient of {with_orientation[0].file.name} is "
                f"{_shown(with_orientation[0].orientation)}, of {s.file.name} {_shown(s.orientation)}",
            )
    orientation = with_orientation[0].orientation if with_orientation else (1.0, 0.0, 0.0, 0.0, 1.0, 0.0)
    row, col = np.array(orientation[:3]), np.array(orientation[3:])
    normal = np.cross(row, col)
    normal /= np.linalg.norm(normal)
    direction = np.column_stack([row, col, normal])
    thickness = next((s.thickness for s in slices if s.thickness is not None), None)
    if not with_position:
        numbers = [s.instance for s in slices]
        if all(n is not None for n in numbers) and len(set(numbers)) == len(numbers):
            slices = sorted(slices, key=lambda s: s.instance)  # type: ignore[arg-type, return-value]
            order = "InstanceNumber"
        else:
            order = "file name"
        dz = thickness or 1.0
        if len(slices) > 1:
            notes.append(
                f"{name}: the slices have no ImagePositionPatient; ordered them by {order}, "
                f"{dz:g} apart ({'SliceThickness' if thickness else 'a guess'})"
            )
        return slices, dz, (0.0, 0.0, 0.0), direction
    where = np.array([np.dot(s.position, normal) for s in slices])  # type: ignore[arg-type]
    order = np.argsort(where, kind="stable")
    slices = [slices[i] for i in order]
    where = where[order]
    if len(slices) == 1:
        return slices, thickness or 1.0, slices[0].position, direction
    gaps = np.diff(where)
    tolerance = 1e-6 + 1e-3 * float(np.median(gaps))
    same = np.flatnonzero(gaps <= tolerance)
    if same.size:
        a, b = slices[same[0]], slices[same[0] + 1]
        raise file_error(
            path,
            f"two slices at the same position: {a.file.name} and {b.file.name} are both at "
            f"{_shown(a.position)} (a duplicated slice, or two series in one folder)",  # type: ignore[arg-type]
        )
    dz = float(where[-1] - where[0]) / (len(slices) - 1)
    if gaps.max() - gaps.min() > 0.01 * dz:
        notes.append(
            f"{name}: the slice positions are {gaps.min():g} to {gaps.max():g} apart (a missing slice?); "
            f"drawn evenly {dz:g} apart"
        )
    start = np.array(slices[0].position)
    offsets = np.array([s.position for s in slices]) - start
    sideways = offsets - np.outer(offsets @ normal, normal)
    if np.linalg.norm(sideways, axis=1).max() > 0.01 * max(dz, min(slices[0].pixel_spacing or (1.0,))):
        notes.append(
            f"{name}: the slices are shifted sideways along the stack (a tilted gantry?); drawn unsheared"
        )
    return slices, dz, slices[0].position, direction


def _values(path: Path, slices: list[_Slice], info: list[str]) -> np.ndarray:
    """values[k, j, i], rescaled per slice into the smallest type that holds them exactly."""
    stored = [s.stored() for s in slices]
    rescaled = any(s.slope != 1.0 or s.intercept != 0.0 for s in slices)
    nz, (ny, nx) = len(slices), stored[0].shape
    if not rescaled:
        dtype = stored[0].dtype.newbyteorder("=")
    else:
        lo, hi = math.inf, -math.inf
        for s, a in zip(slices, stored):
            ends = (s.slope * float(a.min()) + s.intercept, s.slope * float(a.max()) + s.intercept)
            if not all(math.isfinite(e) for e in ends):
                raise file_error(
                    path,
                    f"slice {s.file.name}: RescaleSlope {s.slope:g} and RescaleIntercept {s.intercept:g} "
                    "take its values past the largest float",
                )
            lo, hi = min(lo, *ends), max(hi, *ends)
        integral = all(
            s.slope.is_integer() and s.intercept.is_integer() and max(abs(s.slope), abs(s.intercept)) < 2**31
            for s in slices
        )
        if integral and -(2**15) <= lo and hi < 2**15:
            dtype = np.dtype(np.int16)
        elif integral and -(2**31) <= lo and hi < 2**31:
            dtype = np.dtype(np.int32)
        elif max(abs(lo), abs(hi)) < 1e37 and min(abs(s.slope) for s in slices) > 1e-30:
            dtype = np.dtype(np.float32)  # float32 holds these values without overflow or underflow
        else:
            dtype = np.dtype(np.float64)
        pairs = sorted({(s.slope, s.intercept) for s in slices})
        rule = (
            f"v * {pairs[0][0]:g} + {pairs[0][1]:g}"
            if len(pairs) == 1
            else f"each slice's own ({len(pairs)} differ)"
        )
        info.append(f"applied the DICOM rescale {rule} (as {dtype})")
    check_memory(path, f"{nx}x{ny}x{nz} {dtype}", nx * ny * nz * dtype.itemsize)
    values = np.empty((nz, ny, nx), dtype)
    for k, (s, a) in enumerate(zip(slices, stored)):
        if rescaled and dtype.kind == "f":
            values[k] = a.astype(np.float64) * s.slope + s.intercept
        elif rescaled:
            values[k] = a.astype(np.int64) * int(s.slope) + int(s.intercept)
        else:
            values[k] = a
    return values


def read(path: Path, inspection: Inspection) -> Grid:
    folder = inspection.target
    candidates = _candidates(folder)
    if not candidates:
        raise file_error(path, "holds no DICOM images (looked for .dcm files and files with a DICM header)")
    slices, skipped = [], []
    with warnings.catch_warnings():  # pydicom warns of odd values; what matters is checked here
        warnings.simplefilter("ignore")
        for file in candidates:
            parsed = _parse(path, file, has_dicom_magic(file))
            if parsed is None:
                skipped.append(file.name)
            else:
                slices.append(parsed)
    if not slices:
        raise file_error(path, f"holds no DICOM images (only {', '.join(skipped[:3])}, which hold none)")
    slices = _one_series(path, slices, inspection.facts.get("file"))
    _same_layout(path, slices)
    notes: list[str] = []
    info: list[str] = []
    if skipped:
        info.append(f"skipped {len(skipped)} DICOM file(s) that hold no image ({', '.join(skipped[:3])})")
    if slices[0].pixel_spacing is None:
        notes.append(f"{folder.name}: the slices have no PixelSpacing; took 1 x 1")
    slices, dz, origin, direction = _geometry(path, slices, notes)
    dy, dx = slices[0].pixel_spacing or (1.0, 1.0)
    values = _values(path, slices, info)
    return Grid(
        values,
        (dx, dy, dz),
        tuple(float(v) for v in origin),
        direction,
        notes,
        info,  # type: ignore[arg-type]
        space="LPS",
    )  # DICOM's patient coordinate system


DICOM = FileFormat("DICOM series", (".dcm",), inspect, read=read, array_name=ARRAY_NAME)
