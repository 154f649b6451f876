"""Legacy VTK files (.vtk): STRUCTURED_POINTS become uniform grids, UNSTRUCTURED_GRID tetrahedra.

Quirks of VTK's legacy readers found by truncating files (VTK 9.7):
- binary files cut anywhere report "Error reading binary data!", but only as a *warning*;
- ASCII files cut inside a data block often say nothing at all: the arrays come back at their
  declared size, the missing tail zero-filled or uninitialised. So after an ASCII read we count
  the numbers in the file's data lines and compare them with what the reader returned.
- absurd counts (DIMENSIONS, POINTS, CELLS) are refused here before the reader allocates them.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import BinaryIO

import numpy as np

from volren.errors import file_error
from volren.io._pv import DatasetView, ReadResult
from volren.io.formats.base import FileFormat, Inspection, quote
from volren.io.formats.geometry import check_declared, parse_numbers
from volren.io.limits import DataLayout, check_memory, product

_TYPE_SIZES = {
    "bit": 1, "unsigned_char": 1, "char": 1, "signed_char": 1, "unsigned_short": 2, "short": 2,
    "unsigned_int": 4, "int": 4, "unsigned_long": 8, "long": 8, "vtktypeint64": 8,
    "vtktypeuint64": 8, "vtkidtype": 8, "float": 4, "double": 8,
}  # fmt: skip

_DATASETS = {"STRUCTURED_POINTS": "legacy-image", "UNSTRUCTURED_GRID": "legacy-unstructured"}


class _Lines:
    """Keyword lines of a legacy file, read one at a time so binary blocks can be skipped."""

    def __init__(self, path: Path, f: BinaryIO) -> None:
        self.path, self.f = path, f

    def next(self, what: str, required: bool = True) -> list[str]:
        """The next non-blank line split into words; EOF means the header was cut short."""
        while True:
            raw = self.f.readline(4096)
            if not raw:
                if not required:
                    return []
                raise file_error(self.path, f"truncated: the file ends before its {what}")
            words = raw.decode("latin-1").split()
            if words:
                return words

    def skip(self, nbytes: int) -> None:
        self.f.seek(nbytes, 1)

    @property
    def offset(self) -> int:
        return self.f.tell()


def _int(path: Path, words: list[str], index: int, line: str) -> int:
    try:
        value = int(words[index])
    except (IndexError, ValueError):
        raise file_error(path, f"malformed {line} line: {quote(' '.join(words))}") from None
    if value < 0:
        raise file_error(path, f"negative count in {line} line: {quote(' '.join(words))}")
    return value


def _item_size(path: Path, type_name: str) -> int:
    try:
        return _TYPE_SIZES[type_name.lower()]
    except KeyError:
        raise file_error(path, f"unknown legacy VTK data type {type_name!r}") from None


def inspect(path: Path) -> Inspection:
    with open(path, "rb") as f:
        lines = _Lines(path, f)
        first = f.readline(256).decode("latin-1")
        if not first.startswith("# vtk DataFile Version"):
            raise file_error(path, "not a legacy VTK file (it does not start with '# vtk DataFile Version')")
        version = first[len("# vtk DataFile Version") :].strip()
        if not re.fullmatch(r"[1-5]\.\d", version):
            raise file_error(
                path, f"unknown legacy VTK file version {quote(version)} (volren reads 1.0 to 5.1)"
            )
        f.readline(4096)  # the title: free text
        mode = lines.next("ASCII/BINARY line")[0].upper()
        if mode not in ("ASCII", "BINARY"):
            raise file_error(
                path, f"not a legacy VTK file: the third line must be ASCII or BINARY, got {quote(mode)}"
            )
        words = lines.next("DATASET line")
        if words[0].upper() != "DATASET" or len(words) < 2:
            raise file_error(
                path, f"not a legacy VTK file: expected a DATASET line, got {quote(' '.join(words))}"
            )
        dataset = words[1].upper()
        if dataset not in _DATASETS:
            raise file_error(
                path,
                f"legacy VTK DATASET {dataset} is not a volume; volren reads STRUCTURED_POINTS "
                "(uniform grids) and UNSTRUCTURED_GRID (cells) from .vtk files",
            )
        binary = mode == "BINARY"
        facts: dict = {"ascii": not binary}
        if dataset == "STRUCTURED_POINTS":
            layout = _structured_points(path, lines, binary, facts)
        else:
            layout = _unstructured_grid(path, lines, binary)
    return Inspection(_DATASETS[dataset], path, layout, facts)  # type: ignore[arg-type]


def _structured_points(path: Path, lines: _Lines, binary: bool, facts: dict) -> DataLayout:
    """The data layout; the declared geometry, checked, goes into `facts`."""
    dims: tuple[int, ...] | None = None
    spacing = origin = None
    while True:
        words = lines.next("POINT_DATA or CELL_DATA section (or it holds no scalars)")
        key = words[0].upper()
        if key == "DIMENSIONS":
            dims = tuple(_int(path, words, i, "DIMENSIONS") for i in (1, 2, 3))
        elif key in ("SPACING", "ASPECT_RATIO"):
            spacing = parse_numbers(path, key, " ".join(words[1:]))
        elif key == "ORIGIN":
            origin = parse_numbers(path, key, " ".join(words[1:]))
        elif key in ("POINT_DATA", "CELL_DATA"):
            break
    facts.update(check_declared(path, spacing, origin, "SPACING", "ORIGIN"))
    if dims is None:
        raise file_error(path, "the STRUCTURED_POINTS header has no DIMENSIONS line")
    n = _int(path, words, 1, key)
    expected = product(dims) if key == "POINT_DATA" else product(max(d - 1, 1) for d in dims)
    if n != expected:
        raise file_error(
            path,
            f"dimensions do not match the data: DIMENSIONS {'x'.join(map(str, dims))} means "
            f"{expected:,} {'points' if key == 'POINT_DATA' else 'cells'} but {key} says {n:,}",
        )
    words = lines.next("first data array")
    type_name, ncomp = "unsigned_char", 1
    if words[0].upper() == "SCALARS" and len(words) >= 3:
        type_name = words[2]
        ncomp = _int(path, words, 3, "SCALARS") if len(words) > 3 else 1
    size = _item_size(path, type_name)
    layout = DataLayout(dims, type_name, n * ncomp * size)
    if not (binary and words[0].upper() == "SCALARS"):
        return layout
    data_start = lines.offset
    if lines.f.readline(4096).lstrip().upper().startswith(b"LOOKUP_TABLE"):
        data_start = lines.offset  # the data follows the optional LOOKUP_TABLE line
    nbytes = (n * ncomp + 7) // 8 if type_name.lower() == "bit" else n * ncomp * size
    return DataLayout(dims, type_name, n * ncomp * size, path, data_start, nbytes)


def _unstructured_grid(path: Path, lines: _Lines, binary: bool) -> DataLayout:
    words = lines.next("POINTS line")
    if words[0].upper() == "FIELD":  # global field data first: too rare to walk; VTK reads it
        return DataLayout((0,), "points", 0)
    if words[0].upper() != "POINTS":
        raise file_error(path, f"expected a POINTS line, got {quote(' '.join(words))}")
    n_points = _int(path, words, 1, "POINTS")
    size = _item_size(path, words[2] if len(words) > 2 else "float")
    label = f"{n_points:,} points"
    check_memory(path, label, n_points * 24)
    n_cells = n_ids = 0
    if binary:
        if path.stat().st_size - lines.offset < 3 * n_points * size:
            raise file_error(path, f"truncated: the header declares {label} but the file ends inside them")
        lines.skip(3 * n_points * size)
        words = _cells_line(lines)
        if words:
            n_cells, n_ids = _int(path, words, 1, "CELLS"), _int(path, words, 2, "CELLS")
    else:
        with open(path, "rb") as f:
            f.seek(lines.offset)
            rest = f.read()
        m = re.search(rb"^[ \t]*CELLS\b([^\n]*)\n", rest, re.M)
        if m:
            words = ["CELLS", *m.group(1).decode("latin-1").split()]
            n_cells, n_ids = _int(path, words, 1, "CELLS"), _int(path, words, 2, "CELLS")
            _check_ascii_cells(path, rest[m.end() :], n_cells, n_ids)
    label = f"{n_points:,} points and {n_cells:,} cells ({n_ids:,} ids)"
    return DataLayout((n_points,), "points", n_points * 24 + n_ids * 16 + n_cells * 9, label=label)


def _cells_line(lines: _Lines, limit: int = 64) -> list[str]:
    """The CELLS line after a binary file's points; the text lines between (a version 5 file's
    METADATA block) are passed over. Empty when the file has no CELLS line there."""
    for _ in range(limit):
        words = lines.next("CELLS line", required=False)
        if not words or words[0].upper() in ("CELLS", "CELL_TYPES", "POINT_DATA", "CELL_DATA"):
            return words if words and words[0].upper() == "CELLS" else []
    return []


def _check_ascii_cells(path: Path, block: bytes, n_cells: int, n_ids: int) -> None:
    """The CELLS block of an ASCII file holds what its line declares (VTK's reader crashes or
    hangs when it does not): for versions before 5, n_cells lists of 'count id id ...' adding up
    to n_ids numbers; from 5.0 on, an OFFSETS list of n_cells numbers (0 first, rising, the last
    n_ids) and a CONNECTIVITY list of n_ids."""
    text = block.decode("latin-1")
    if text.lstrip().upper().startswith("OFFSETS"):
        body = text.lstrip().split("\n", 1)[1] if "\n" in text.lstrip() else ""
        offsets = _numbers(body, n_cells)
        ok = len(offsets) == n_cells and (n_cells == 0 or (offsets[0] == 0 and offsets[-1] == n_ids))
        if not ok or (np.diff(offsets) < 0).any():
            raise file_error(
                path,
                f"the CELLS line declares {n_cells:,} offsets ending at {n_ids:,} ids; "
                "the OFFSETS list does not match",
            )
        return
    numbers = _numbers(text, n_ids)
    if len(numbers) < n_ids:
        raise file_error(
            path, f"truncated: the CELLS line declares {n_ids:,} numbers, {len(numbers):,} follow"
        )
    per_cell = n_ids // n_cells if n_cells else 0
    if per_cell and n_ids % n_cells == 0 and (numbers[::per_cell] == per_cell - 1).all():
        return  # the usual case: cells of one size (all tetrahedra), checked without a loop
    position = 0
    for _ in range(n_cells):
        if position >= n_ids or numbers[position] < 1:
            raise file_error(
                path,
                f"the CELLS line declares {n_cells:,} cells in {n_ids:,} numbers; the list does not add up",
            )
        position += 1 + int(numbers[position])
    if position != n_ids:
        raise file_error(
            path,
            f"the CELLS line declares {n_cells:,} cells in {n_ids:,} numbers; the list holds {position:,}",
        )


def _numbers(text: str, count: int) -> np.ndarray:
    """Up to `count` leading integers of `text` (fewer where a keyword or the end comes first)."""
    words = text.split(None, count)[:count]
    try:
        return np.array(words, dtype=np.int64)  # the usual case, converted in C
    except (ValueError, OverflowError):
        pass
    values = []
    for word in words:
        try:
            value = int(word)
        except ValueError:
            break
        if not -(2**63) <= value < 2**63:
            break
        values.append(value)
    return np.array(values, dtype=np.int64)


# --------------------------------------------------------------------- ASCII completeness

_NON_DATA_LINE = re.compile(rb"^[ \t]*(?![-+]?(?:\d|\.\d|nan|inf))\S[^\n]*", re.M | re.I)


def count_data_numbers(data: bytes) -> int:
    """Whitespace-separated tokens on lines that start with a number (the data lines)."""
    # skip the version line and the free-text title
    body = data.split(b"\n", 2)[2] if data.count(b"\n", 0, 4096) >= 2 else b""
    arr = np.frombuffer(body, dtype=np.uint8)
    if arr.size == 0:
        return 0
    space = arr <= 32
    tokens = int(np.count_nonzero(~space[1:] & space[:-1])) + int(not space[0])
    for m in _NON_DATA_LINE.finditer(body):
        tokens -= len(m.group(0).split())
    return tokens


def _numeric_size(arrays) -> int:
    return sum(int(a.size) for a in arrays.values() if a.dtype.kind in "biuf")


def check_output(path: Path, view: DatasetView, result: ReadResult, inspection: Inspection) -> DatasetView:
    """ASCII files: the data lines must hold at least as many numbers as the reader returned."""
    if not inspection.facts.get("ascii"):
        return view
    data = path.read_bytes()
    expected = (
        _numeric_size(view.point_arrays) + _numeric_size(view.cell_arrays) + _numeric_size(view.field_arrays)
    )
    if view.kind == "unstructured":
        has_offsets = re.search(rb"^[ \t]*OFFSETS\b", data, re.M) is not None
        expected += (
            3 * view.n_points + view.n_connectivity + 2 * view.n_cells + int(has_offsets and view.n_cells > 0)
        )
    found = count_data_numbers(data)
    if found < expected:
        raise file_error(
            path,
            f"truncated: its data lines hold {found:,} numbers but its header declares {expected:,}",
        )
    return view


LEGACY = FileFormat("legacy VTK", (".vtk",), inspect, check_output)
