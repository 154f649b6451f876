"""VTK XML files (.vti image data, .vtu unstructured grids).

The readers report truncation, but cryptically, and a WholeExtent larger than memory aborts the
process with std::bad_alloc; so the extent, the piece sizes and the closing tag are checked here.
A .vti data array longer than its piece's extent is read in part without a word (the first
values, laid out on the smaller grid), so the lengths the arrays declare are checked too.
"""

from __future__ import annotations

import base64
import mmap
import re
from pathlib import Path

import numpy as np

from volren.errors import file_error
from volren.io.formats.base import FileFormat, Inspection, read_head
from volren.io.formats.geometry import check_declared, parse_numbers
from volren.io.limits import DataLayout, product

_TYPE_SIZES = {
    "Int8": 1, "UInt8": 1, "Int16": 2, "UInt16": 2, "Int32": 4, "UInt32": 4,
    "Int64": 8, "UInt64": 8, "Float32": 4, "Float64": 8, "Bit": 1, "String": 1,
}  # fmt: skip


def _attr(tag: str, name: str) -> str | None:
    m = re.search(rf'\b{name}\s*=\s*"([^"]*)"', tag)
    return m.group(1) if m else None


def _check_xml(path: Path, expected: str) -> str:
    """The head of the file as text, after making sure it is a complete VTK XML file of `expected`."""
    head = read_head(path).decode("latin-1")
    if not head.lstrip("\ufeff \t\r\n").startswith("<"):
        raise file_error(
            path, f"not a VTK XML file (it does not start with '<'), so not a .{_SUFFIX[expected]}"
        )
    size = path.stat().st_size
    with open(path, "rb") as f:
        f.seek(max(0, size - 4096))
        tail = f.read().rstrip()
    if not tail.endswith(b"</VTKFile>"):
        raise file_error(path, "truncated: the XML ends before its closing </VTKFile> tag")
    tag = re.search(r"<VTKFile\b[^>]*>", head)
    kind = _attr(tag.group(0), "type") if tag else None
    if kind != expected:
        raise file_error(
            path, f"holds VTK XML data of type {kind!r}, not {expected} as .{_SUFFIX[expected]} files do"
        )
    _check_attributes(path, head.split("<AppendedData")[0])
    return head


_SUFFIX = {"ImageData": "vti", "UnstructuredGrid": "vtu"}


_HEADER_TYPES = ("UInt32", "UInt64")
_COMPRESSORS = ("vtkZLibDataCompressor", "vtkLZ4DataCompressor", "vtkLZMADataCompressor")
_FORMATS = ("ascii", "binary", "appended")
_MAX_COMPONENTS = 1 << 16


def _check_attributes(path: Path, head: str) -> None:
    """The attributes VTK's XML readers trust: a wrong one crashes them (a String or negative-
    component point array, a header type other than UInt32/UInt64, a negative count)."""
    tag = re.search(r"<VTKFile\b[^>]*>", head)
    root = tag.group(0) if tag else ""
    for name, allowed in (("header_type", _HEADER_TYPES), ("compressor", _COMPRESSORS),
                          ("byte_order", ("LittleEndian", "BigEndian"))):  # fmt: skip
        value = _attr(root, name)
        if value is not None and value not in allowed:
            raise file_error(path, f"<VTKFile {name}={value!r}> is not one of {', '.join(allowed)}")
    field_data = [(m.start(), m.end()) for m in re.finditer(r"<FieldData\b.*?(</FieldData>|$)", head, re.S)]
    for m in re.finditer(r"<DataArray\b[^>]*>", head):
        tag = m.group(0)
        name = _attr(tag, "Name") or "(unnamed)"
        kind = _attr(tag, "type")
        in_field_data = any(a <= m.start() < b for a, b in field_data)
        if kind not in _TYPE_SIZES or (kind == "String" and not in_field_data):
            raise file_error(path, f"data array {name!r} has type {kind!r}; volren reads numeric arrays")
        components = _attr(tag, "NumberOfComponents")
        if components is not None and not (components.isdigit() and 0 < int(components) <= _MAX_COMPONENTS):
            raise file_error(path, f"data array {name!r} has NumberOfComponents={components!r}")
        layout = _attr(tag, "format")
        if layout is not None and layout not in _FORMATS:
            raise file_error(
                path, f"data array {name!r} has format={layout!r}; expected {', '.join(_FORMATS)}"
            )
        offset = _attr(tag, "offset")
        if offset is not None and not offset.isdigit():
            raise file_error(path, f"data array {name!r} has offset={offset!r}")


def _bytes_per_item(head: str) -> int:
    """Bytes per point (or cell) over the data arrays declared in the head of the file."""
    total = 0
    for tag in re.findall(r"<DataArray\b[^>]*>", head):
        size = _TYPE_SIZES.get(_attr(tag, "type") or "", 1)
        total += size * int(_attr(tag, "NumberOfComponents") or 1)
    return max(total, 1)


_TAGS = re.compile(rb"<(/?)(Piece|PointData|CellData|DataArray|AppendedData)\b([^>]*)>")
_SPACE = re.compile(rb"\s*")
_WORDS_CHUNK = 1 << 24


def _extent_counts(extent: str | None) -> tuple[int, int] | None:
    """(points, cells) of a piece's Extent, None when it is not six integers."""
    try:
        e = [int(v) for v in (extent or "").split()]
    except ValueError:
        return None
    if len(e) != 6:
        return None
    sizes = [e[2 * a + 1] - e[2 * a] for a in range(3)]
    return product(n + 1 for n in sizes), product(max(n, 1) for n in sizes)


def _check_array_lengths(path: Path, head: str) -> None:
    """Refuse a point or cell data array that holds more values than its piece's Extent has
    points or cells (times its components)."""
    root = re.search(r"<VTKFile\b[^>]*>", head)
    tag = root.group(0) if root else ""
    header = (8 if _attr(tag, "header_type") == "UInt64" else 4, ">" if _attr(tag, "byte_order") == "BigEndian" else "<",
              _attr(tag, "compressor") is not None)  # fmt: skip
    with open(path, "rb") as f, mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as data:
        arrays, appended = [], None
        counts, section = None, ""
        for m in _TAGS.finditer(data):
            closing, name, attributes = m.group(1), m.group(2).decode(), m.group(3).decode("latin-1")
            if name == "AppendedData":
                appended = (m.end(), _attr(attributes, "encoding") or "raw")
                break
            if name == "Piece" and not closing:
                counts = _extent_counts(_attr(attributes, "Extent"))
            elif name in ("PointData", "CellData"):
                section = "" if closing else name
            elif name == "DataArray" and section and counts is not None:
                arrays.append((attributes, counts[section == "CellData"], section, m.end()))
        for attributes, count, section, start in arrays:
            stored = _stored_values(data, attributes, start, appended, header)
            components = int(_attr(attributes, "NumberOfComponents") or 1)
            if stored is not None and stored > count * components:
                items = "points" if section == "PointData" else "cells"
                raise file_error(
                    path, f"data array {_attr(attributes, 'Name') or '(unnamed)'!r} holds {stored:,} values, more than "
                    f"the {count:,} {items} x {components} of its piece's Extent: the Extent is smaller than the data"
                )  # fmt: skip


def _stored_values(data: mmap.mmap, attributes: str, start: int, appended: tuple[int, str] | None,
                   header: tuple[int, str, bool]) -> int | None:  # fmt: skip
    """How many values a data array holds by its own account (None when that cannot be told:
    the reader's checks then speak)."""
    kind, layout = _attr(attributes, "type"), _attr(attributes, "format") or "ascii"
    size = _TYPE_SIZES.get(kind or "")
    if size is None or kind in ("Bit", "String"):
        return None
    if layout == "ascii":
        return _count_words(data, start, data.find(b"<", start))
    if layout == "binary":
        position, encoding = start, "base64"
    elif appended is not None and (_attr(attributes, "offset") or "").isdigit():
        underscore = data.find(b"_", appended[0])
        position, encoding = underscore + 1 + int(_attr(attributes, "offset") or 0), appended[1]
    else:
        return None
    stored = _stored_bytes(data, position, encoding, header)
    return None if stored is None else stored // size


def _stored_bytes(data: mmap.mmap, position: int, encoding: str, header: tuple[int, str, bool]) -> int | None:
    """The bytes of values a binary array's header declares (uncompressed: one integer; compressed:
    the block count, block size and last block's size)."""
    int_size, order, compressed = header
    need = int_size * (3 if compressed else 1)
    if encoding == "base64":
        position = _SPACE.match(data, position).end()
        try:
            raw = base64.b64decode(data[position : position - (-need // 3) * 4])
        except ValueError:
            return None
    else:
        raw = data[position : position + need]
    if len(raw) < need:
        return None
    ints = [int(v) for v in np.frombuffer(raw[:need], dtype=f"{order}u{int_size}")]
    if not compressed:
        return ints[0]
    blocks, block, last = ints
    return blocks * block if last == 0 or blocks == 0 else (blocks - 1) * block + last


def _count_words(data: mmap.mmap, start: int, end: int) -> int:
    """Whitespace-separated words between two offsets, a chunk at a time."""
    words, after_space = 0, True
    for chunk_start in range(start, max(end, start), _WORDS_CHUNK):
        chunk = np.frombuffer(data[chunk_start : min(chunk_start + _WORDS_CHUNK, end)], np.uint8)
        space = np.isin(chunk, (32, 9, 10, 13))
        starts = ~space & np.concatenate([[after_space], space[:-1]])
        words += int(starts.sum())
        after_space = bool(space[-1])
    return words


def inspect_vti(path: Path) -> Inspection:
    head = _check_xml(path, "ImageData")
    tag = re.search(r"<ImageData\b[^>]*>", head)
    extent = _attr(tag.group(0), "WholeExtent") if tag else None
    try:
        e = [int(v) for v in (extent or "").split()]
        if len(e) != 6:
            raise ValueError
    except ValueError:
        raise file_error(path, f"the <ImageData> element has no valid WholeExtent (got {extent!r})") from None
    dims = (e[1] - e[0] + 1, e[3] - e[2] + 1, e[5] - e[4] + 1)
    if min(dims) <= 0:
        raise file_error(path, f"the grid is empty (WholeExtent {extent!r})")
    for piece in re.findall(r"<Piece\b[^>]*>", head):
        text = _attr(piece, "Extent")
        try:
            p = [int(v) for v in (text or "").split()]
        except ValueError:
            p = []
        inside = len(p) == 6 and all(e[2 * a] <= p[2 * a] <= p[2 * a + 1] <= e[2 * a + 1] for a in range(3))
        if not inside:
            raise file_error(path, f"a <Piece> Extent {text!r} is not inside the WholeExtent {extent!r}")
    _check_array_lengths(path, head)
    per_point = _bytes_per_item(head)
    layout = DataLayout(dims, f"grid of {per_point}-byte points", product(dims) * per_point)
    spacing = parse_numbers(path, "Spacing", _attr(tag.group(0), "Spacing")) if tag else None
    origin = parse_numbers(path, "Origin", _attr(tag.group(0), "Origin")) if tag else None
    return Inspection("vti", path, layout, check_declared(path, spacing, origin, "Spacing", "Origin"))


def inspect_vtu(path: Path) -> Inspection:
    head = _check_xml(path, "UnstructuredGrid")
    n_points = n_cells = 0
    for tag in re.findall(r"<Piece\b[^>]*>", head):
        points, cells = _attr(tag, "NumberOfPoints") or "0", _attr(tag, "NumberOfCells") or "0"
        if not (points.isdigit() and cells.isdigit()):
            raise file_error(
                path, f"a <Piece> has NumberOfPoints={points!r} NumberOfCells={cells!r}: not counts"
            )
        n_points += int(points)
        n_cells += int(cells)
    # points as float64 xyz plus their arrays; cells as connectivity, offsets and types
    memory = n_points * (24 + _bytes_per_item(head)) + n_cells * (8 * 8 + 1)
    label = f"{n_points:,} points and {n_cells:,} cells"
    return Inspection("vtu", path, DataLayout((n_points,), label, memory, label=label))


VTI = FileFormat("VTK XML image data", (".vti",), inspect_vti)
VTU = FileFormat("VTK XML unstructured grid", (".vtu",), inspect_vtu)
