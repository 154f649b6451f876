"""NRRD (.nrrd with the data attached, .nhdr with a separate data file).

Quirks of vtkNrrdReader (VTK 9.7), each handled here:
- it hangs forever on a header whose last line has no line break (a file cut inside its header,
  or a magic line followed by garbage), and aborts (std::bad_alloc) on absurd sizes: the header
  is parsed and checked before the reader sees it;
- it guesses that a first axis of 9 samples or fewer is a vector axis ("sizes: 7 5 4" comes back
  as a 5x4x1 grid of 7-component vectors); when the header says that axis is spatial, the grid
  is put back;
- it keeps only the lengths of 'space directions' (the rotation is reported as ignored);
- for raw data in a left-handed 'space' (LAS) it flips the rows, and gzip data it never
  byte-swaps (big-endian gzip comes back garbled): both are undone. (Its gzip path does not flip
  LAS rows.)
- for ASCII data it returns unfilled memory: volren parses ASCII data itself (`read`);
- for gzip data it reads whatever is there through zlib's gzread, which passes bytes that are not
  gzip through as they are and turns a zlib stream into garbage: gzip data must start with gzip's
  magic bytes.
"""

from __future__ import annotations

import re
from dataclasses import replace
from pathlib import Path

import numpy as np

from volren.errors import file_error
from volren.io._pv import DatasetView, ReadResult
from volren.io.formats.base import FileFormat, Grid, Inspection, quote, read_head
from volren.io.formats.geometry import check_declared, parse_numbers
from volren.io.limits import DataLayout, product
from volren.model.anatomy import NRRD_SPACES

_TYPES = {
    1: ("signed char", "int8", "int8_t", "uchar", "unsigned char", "uint8", "uint8_t"),
    2: ("short", "short int", "signed short", "signed short int", "int16", "int16_t", "ushort",
        "unsigned short", "unsigned short int", "uint16", "uint16_t"),
    4: ("int", "signed int", "int32", "int32_t", "uint", "unsigned int", "uint32", "uint32_t", "float"),
    8: ("longlong", "long long", "long long int", "signed long long", "signed long long int", "int64",
        "int64_t", "ulonglong", "unsigned long long", "unsigned long long int", "uint64", "uint64_t",
        "double"),
}  # fmt: skip
_TYPE_SIZES = {name: size for size, names in _TYPES.items() for name in names}
_RAW = ("raw",)
_GZIP = ("gzip", "gz")
_GZIP_MAGIC = b"\x1f\x8b"
_TEXT = ("ascii", "text", "txt")
_HEADER_LIMIT = 1 << 20
_SPATIAL_KINDS = ("domain", "space", "time", "none", "???")
_KINDS = frozenset(
    """domain space time list point vector covariant-vector normal stub scalar complex 2-vector 3-color
    rgb-color hsv-color xyz-color 4-color rgba-color 3-vector 3-gradient 3-normal 4-vector quaternion
    2d-symmetric-matrix 2d-masked-symmetric-matrix 2d-matrix 2d-masked-matrix 3d-symmetric-matrix
    3d-masked-symmetric-matrix 3d-matrix 3d-masked-matrix none ???""".split()
)
_LEFT_HANDED = ("left-anterior-superior", "las", "3d-left-handed")


def _header(path: Path) -> tuple[dict[str, str], int]:
    """Fields (keys lower-cased, spaces removed) and the offset of the first byte after the header."""
    head = read_head(path, _HEADER_LIMIT)
    if not re.match(rb"NRRD000\d\r?\n", head):
        raise file_error(path, "not a NRRD file (it does not start with a 'NRRD000x' magic line)")
    fields: dict[str, str] = {}
    offset = 0
    lines = head.split(b"\n")
    for number, raw in enumerate(lines):
        is_last = number == len(lines) - 1
        if is_last and raw:  # the file (or our read limit) ends inside a header line
            raise file_error(
                path,
                "truncated: the NRRD header's last line has no line break (VTK's reader would hang on it)",
            )
        offset += len(raw) + (0 if is_last else 1)
        line = raw.decode("latin-1").rstrip("\r")
        if number == 0 or line.startswith("#"):
            continue
        if not line:
            return fields, offset
        if ":=" in line:
            continue  # key/value pairs: free-form metadata
        key, sep, value = line.partition(": ")
        if not sep or not line.isprintable():
            raise file_error(
                path, f"not a valid NRRD header: line {number + 1} {quote(line)} is not 'field: value'"
            )
        field = key.strip().lower().replace(" ", "")
        if field in fields:  # the format allows each field once; VTK's reader crashes on some twice
            raise file_error(path, f"not a valid NRRD header: the field {key.strip()!r} appears twice")
        fields[field] = value.strip()
    return fields, -1  # no blank line: a detached header that ends at end of file


def _directions(text: str | None, n_axes: int) -> np.ndarray | None:
    """The 'space directions' of the spatial axes, one per row (None when absent, or when they
    are not three 3-vectors: a 2D image or a space of other dimension); ValueError when
    malformed: a word that is neither a vector nor 'none', a count that is not the dimension,
    a non-finite entry, a zero vector, or three vectors that span no volume."""
    if text is None:
        return None
    words = re.findall(r"\([^)]*\)|[^\s()]+", text)
    if len(words) != n_axes or any(w != "none" and not w.startswith("(") for w in words):
        raise ValueError(text)
    vectors = [[float(v) for v in w.strip("()").split(",")] for w in words if w != "none"]
    if len(vectors) != 3 or any(len(v) != 3 for v in vectors):
        return None
    rows = np.array(vectors, dtype=np.float64)
    lengths = np.linalg.norm(rows, axis=1)
    if not np.isfinite(rows).all() or (lengths == 0).any():
        raise ValueError(text)
    if abs(np.linalg.det(rows / lengths[:, None])) < 1e-6:
        raise ValueError(text)
    return rows


def _geometry(fields: dict[str, str], dims: tuple[int, ...]) -> dict:
    """What the later steps need: spacing and direction per axis, and VTK's misreadings to undo."""
    directions = _directions(fields.get("spacedirections"), len(dims))
    if directions is not None:
        spacing = np.linalg.norm(directions, axis=1)
        direction = (directions / np.where(spacing == 0, 1, spacing)[:, None]).T  # columns = axes
    else:
        direction = None
        try:
            spacing = np.array([float(v) for v in fields.get("spacings", "").split()] or [1.0, 1.0, 1.0])
        except ValueError:
            spacing = np.ones(3)
    kinds = fields.get("kinds", "").lower().split()
    first_is_spatial = len(dims) == 3 and (not kinds or kinds[0] in _SPATIAL_KINDS)
    vtk_splits_first = len(dims) > 3 or (bool(dims) and dims[0] <= 9)
    return {
        "direction": direction,
        "space": NRRD_SPACES.get(fields.get("space", "").strip().lower()),  # a patient system, if named
        # three spatial axes: as declared (checked in `inspect`; negative mirrors the axis); else
        # the first three, NaN for non-spatial ones (vector components) made 1
        "spacing": tuple(float(s) for s in spacing[:3])
        if len(dims) == 3 and first_is_spatial
        else tuple(float(s) if s > 0 else 1.0 for s in spacing[:3]),
        "sizes": dims,
        "unsplit": first_is_spatial and vtk_splits_first and len(spacing) == 3,
    }


def inspect(path: Path) -> Inspection:
    fields, header_end = _header(path)
    for key in ("type", "dimension", "sizes", "encoding"):
        if key not in fields:
            raise file_error(path, f"not a valid NRRD header: it has no '{key}' field")
    try:
        dims = tuple(int(v) for v in fields["sizes"].split())
    except ValueError:
        raise file_error(path, f"malformed NRRD sizes {fields['sizes']!r}") from None
    if not dims or min(dims) <= 0:
        raise file_error(path, f"malformed NRRD sizes {fields['sizes']!r}")
    dimension = fields["dimension"]
    if not dimension.isdigit() or int(dimension) != len(dims) or not 1 <= len(dims) <= 16:
        raise file_error(
            path, f"NRRD dimension {dimension!r} does not match its {len(dims)} sizes {fields['sizes']!r}"
        )
    kinds = fields.get("kinds", "").lower().split()
    if "kinds" in fields and (len(kinds) != len(dims) or not set(kinds) <= _KINDS):
        raise file_error(path, f"malformed NRRD kinds {quote(fields['kinds'])}: one known kind per axis")
    type_name = fields["type"].lower()
    if type_name not in _TYPE_SIZES:
        raise file_error(path, f"unsupported NRRD type {fields['type']!r}")
    nbytes = product(dims) * _TYPE_SIZES[type_name]
    try:
        facts = _geometry(fields, dims)
    except ValueError:
        raise file_error(
            path,
            f"malformed NRRD space directions {quote(fields['spacedirections'])}: one finite, non-zero "
            "vector (or 'none') per axis, spanning a volume",
        ) from None
    if (
        len(dims) == 3
        and len(facts["spacing"]) == 3
        and "spacings" in fields
        and "spacedirections" not in fields
    ):
        declared_spacing = facts["spacing"]
    else:
        declared_spacing = None
    origin = parse_numbers(path, "space origin", fields.get("spaceorigin"))
    check_declared(path, declared_spacing, origin, "spacings", "space origin")
    encoding = fields["encoding"].lower()
    if encoding in _RAW and fields.get("space", "").lower() in _LEFT_HANDED:
        # VTK flips its rows: our y, or our z when it took our x for vector components
        facts["flip_axis"] = 0 if facts["unsplit"] else 1
        facts["left_handed_space"] = fields["space"]
    facts["swap_bytes"] = encoding in _GZIP and fields.get("endian") == "big" and _TYPE_SIZES[type_name] > 1
    layout = DataLayout(dims, type_name, nbytes)
    data_name = fields.get("datafile", "")
    if header_end < 0 and not data_name:
        raise file_error(
            path, "truncated: the NRRD header is not ended by a blank line and names no data file"
        )
    if encoding in _TEXT:
        return _text_inspection(path, fields, dims, facts, layout, origin, header_end)
    one_data_file = not data_name.upper().startswith("LIST") and " " not in data_name
    if encoding in _GZIP and one_data_file:
        _check_gzip_start(path, fields, data_name, header_end)
    if encoding not in _RAW or not one_data_file:
        return Inspection("nrrd", path, layout, facts)  # compressed: VTK reports short data
    try:
        skip, line_skip = int(fields.get("byteskip", "0") or 0), int(fields.get("lineskip", "0") or 0)
    except ValueError:
        raise file_error(path, "malformed NRRD header: byte skip and line skip must be integers") from None
    if skip < 0 or line_skip != 0:
        return Inspection("nrrd", path, layout, facts)
    data_file, offset = (path.parent / data_name, skip) if data_name else (path, header_end + skip)
    return Inspection("nrrd", path, DataLayout(dims, type_name, nbytes, data_file, offset, nbytes), facts)


def _check_gzip_start(path: Path, fields: dict[str, str], data_name: str, header_end: int) -> None:
    """Data declared gzip must start (after its line skip) with gzip's magic bytes."""
    data_file, offset = (path.parent / data_name, 0) if data_name else (path, header_end)
    if not data_file.is_file():
        raise file_error(path, f"the data file {data_name!r} named in the header is missing")
    try:
        line_skip = int(fields.get("lineskip", "0") or 0)
    except ValueError:
        raise file_error(path, "malformed NRRD header: byte skip and line skip must be integers") from None
    with open(data_file, "rb") as f:
        f.seek(offset)
        for _ in range(line_skip):
            f.readline()
        start = f.read(len(_GZIP_MAGIC))
    if start != _GZIP_MAGIC:
        where = f" in {data_file.name}" if data_name else ""
        raise file_error(path, f"the header says 'encoding: gzip' but the data{where} is not gzip (it does not "
                               f"start with gzip's bytes 1f 8b but {start.hex(' ') or 'nothing'})")  # fmt: skip


def _text_dtype(type_name: str) -> np.dtype:
    size = _TYPE_SIZES[type_name]
    if type_name in ("float", "double"):
        return np.dtype(f"f{size}")
    unsigned = type_name.startswith(("u", "unsigned")) or type_name in ("uchar",)
    return np.dtype(f"{'u' if unsigned else 'i'}{size}")


def _text_inspection(path: Path, fields: dict[str, str], dims: tuple[int, ...], facts: dict,
                     layout: DataLayout, origin: tuple | None, header_end: int) -> Inspection:  # fmt: skip
    """What `read` needs for ASCII data: one data file (or the rest of this one), three or two
    spatial axes of scalars."""
    data_name = fields.get("datafile", "")
    if data_name.upper().startswith("LIST") or " " in data_name:
        raise file_error(
            path, f"ASCII data in several files ({quote(data_name)}) is not supported; give one data file"
        )
    kinds = fields.get("kinds", "").lower().split()
    if len(dims) not in (2, 3) or any(k not in _SPATIAL_KINDS for k in kinds):
        raise file_error(
            path, f"ASCII NRRD of {len(dims)} axes (kinds {quote(fields.get('kinds', 'none given'))}) is not "
            "supported: volren reads ASCII data on 2 or 3 spatial axes"
        )  # fmt: skip
    try:
        line_skip = int(fields.get("lineskip", "0") or 0)
        byte_skip = int(fields.get("byteskip", "0") or 0)
    except ValueError:
        raise file_error(path, "malformed NRRD header: byte skip and line skip must be integers") from None
    if line_skip < 0 or byte_skip != 0:
        raise file_error(path, "ASCII NRRD data takes a line skip of 0 or more and no byte skip")
    facts.update(text=(path.parent / data_name if data_name else path, line_skip, fields["type"].lower()),
                 data_start=max(header_end, 0), origin=origin)  # fmt: skip
    if len(dims) == 2:
        facts["spacing"] = (*facts["spacing"][:2], 1.0)
        facts["unsplit"] = False
    return Inspection("nrrd", path, layout, facts)


def read(path: Path, inspection: Inspection) -> Grid | None:
    """ASCII data, parsed here: vtkNrrdReader (VTK 9.7) returns unfilled memory for every ASCII
    file, whole or cut. Other encodings: None, for VTK's reader."""
    text = inspection.facts.get("text")
    if text is None:
        return None
    data_file, line_skip, type_name = text
    sizes = inspection.facts["sizes"]
    expected = product(sizes)
    try:
        with open(data_file, "rb") as f:
            if data_file == path:
                f.seek(inspection.facts["data_start"])
            for _ in range(line_skip):
                f.readline()
            text = f.read()
    except OSError as exc:
        raise file_error(
            path, f"cannot read its ASCII data {quote(str(data_file))}: {exc.strerror}"
        ) from None
    try:
        numbers = np.fromstring(text, dtype=np.float64, sep=" ")  # in C: no Python object per number
    except ValueError:
        raise file_error(path, "its ASCII data holds a word that is not a number") from None
    if numbers.size < expected:
        raise file_error(
            path, f"truncated: its ASCII data has {numbers.size:,} numbers, the sizes declare {expected:,}"
        )
    if numbers.size > expected:
        raise file_error(
            path, f"its ASCII data has {numbers.size:,} numbers, more than the {expected:,} the sizes declare"
        )
    dtype = _text_dtype(type_name)
    if dtype.kind in "iu":
        info = np.iinfo(dtype)
        bad = (
            ~np.isfinite(numbers)
            | (numbers != np.round(numbers))
            | (numbers < info.min)
            | (numbers > info.max)
        )
        if bad.any():
            at = int(np.argmax(bad))
            raise file_error(path, f"ASCII number {at + 1:,} ({numbers[at]:g}) is not a {type_name}")
    nx, ny, nz = (*sizes, 1)[:3]
    values = numbers.astype(dtype).reshape(nz, ny, nx)
    origin = inspection.facts.get("origin") or (0.0, 0.0, 0.0)
    spacing = inspection.facts["spacing"] if len(sizes) == 3 else (*inspection.facts["spacing"][:2], 1.0)
    return Grid(
        values, spacing, origin, inspection.facts.get("direction"), space=inspection.facts.get("space")
    )


def check_output(path: Path, view: DatasetView, result: ReadResult, inspection: Inspection) -> DatasetView:
    """Undo VTK's guess that a short first axis holds vector components."""
    facts = inspection.facts
    if not facts.get("unsplit") or view.dimensions[2] != 1:
        return view
    nx, ny, nz = facts["sizes"]
    arrays = {name: a.reshape(-1) for name, a in view.point_arrays.items()}  # same memory order
    return replace(
        view, point_arrays=arrays, dimensions=(nx, ny, nz), spacing=facts["spacing"], n_points=nx * ny * nz
    )


def adjust(grid: Grid, result: ReadResult, inspection: Inspection) -> Grid:
    """Undo VTK's row flip and missing byte swap; pass the ignored rotation on to be reported."""
    if "flip_axis" in inspection.facts:
        grid.values = np.ascontiguousarray(np.flip(grid.values, axis=inspection.facts["flip_axis"]))
        grid.notes.append(_mirrored_note(inspection))
    if inspection.facts.get("swap_bytes"):
        grid.values = grid.values.byteswap()
    grid.direction = inspection.facts.get("direction")
    grid.space = inspection.facts.get("space")
    return grid


def _mirrored_note(inspection: Inspection) -> str:
    """Say that VTK-based tools show this file mirrored: volren keeps the file's own order."""
    axis = "z" if inspection.facts["flip_axis"] == 0 else "y"
    return (f"{inspection.target.name}: drawn in the file's own order; VTK, ParaView and PyVista mirror its "
            f"left-handed space {inspection.facts['left_handed_space']!r} in {axis}")  # fmt: skip


NRRD = FileFormat("NRRD", (".nrrd", ".nhdr"), inspect, check_output, adjust, read, array_name="ImageFile")
