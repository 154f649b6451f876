"""VTK XML files (.vti image data, .vtu unstructured grids).

The readers report truncation, but cryptically, and a WholeExtent larger than memory aborts the
process with std::bad_alloc; so the extent, the piece sizes and the closing tag are checked here.
"""

from __future__ import annotations

import re
from pathlib import Path

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
    return head


_SUFFIX = {"ImageData": "vti", "UnstructuredGrid": "vtu"}


def _bytes_per_item(head: str) -> int:
    """Bytes per point (or cell) over the data arrays declared in the head of the file."""
    total = 0
    for tag in re.findall(r"<DataArray\b[^>]*>", head):
        size = _TYPE_SIZES.get(_attr(tag, "type") or "", 1)
        total += size * int(_attr(tag, "NumberOfComponents") or 1)
    return max(total, 1)


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
    per_point = _bytes_per_item(head)
    layout = DataLayout(dims, f"grid of {per_point}-byte points", product(dims) * per_point)
    spacing = parse_numbers(path, "Spacing", _attr(tag.group(0), "Spacing")) if tag else None
    origin = parse_numbers(path, "Origin", _attr(tag.group(0), "Origin")) if tag else None
    return Inspection("vti", path, layout, check_declared(path, spacing, origin, "Spacing", "Origin"))


def inspect_vtu(path: Path) -> Inspection:
    head = _check_xml(path, "UnstructuredGrid")
    n_points = n_cells = 0
    for tag in re.findall(r"<Piece\b[^>]*>", head):
        try:
            n_points += int(_attr(tag, "NumberOfPoints") or 0)
            n_cells += int(_attr(tag, "NumberOfCells") or 0)
        except ValueError:
            raise file_error(path, f"a <Piece> element has non-integer sizes: {tag[:120]}") from None
    # points as float64 xyz plus their arrays; cells as connectivity, offsets and types
    memory = n_points * (24 + _bytes_per_item(head)) + n_cells * (8 * 8 + 1)
    label = f"{n_points:,} points and {n_cells:,} cells"
    return Inspection("vtu", path, DataLayout((n_points,), label, memory, label=label))


VTI = FileFormat("VTK XML image data", (".vti",), inspect_vti)
VTU = FileFormat("VTK XML unstructured grid", (".vtu",), inspect_vtu)
