"""What every file format module provides, and the record a volume passes through on its way in.

Loading is: `inspect` the header ourselves (garbage, truncation, sizes; nothing VTK-specific), let
one VTK reader read the file, `check_output` for what the reader got wrong without saying so (and
undo what it misread), then `adjust` the grid for what the reader knows but does not apply
(origins kept in side matrices, value scaling, axis flips).

A format whose VTK reader cannot be made safe (SLC, DICOM, ASCII NRRD) has its own `read` instead:
it returns the grid itself, and no VTK reader sees the file.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from volren.io._pv import DatasetView, ReaderName, ReadResult
from volren.io.limits import DataLayout

HEAD_BYTES = 1 << 16


@dataclass
class Grid:
    """A uniform grid between the reader and the model: values[k, j, i], geometry in xyz.

    `notes` are repairs and things ignored (each also becomes a VolrenWarning); `info` notes only
    record what loading did. `scalars` names the field the values are and `arrays` every field the
    file offers (`volren.io.dataset.array_choices`; empty for formats with one field).
    """

    values: NDArray
    spacing: tuple[float, float, float]
    origin: tuple[float, float, float]
    direction: NDArray | None = None
    notes: list[str] = field(default_factory=list)
    info: list[str] = field(default_factory=list)
    scalars: str = ""
    arrays: tuple[str, ...] = ()
    #: the patient coordinate system `direction` is given in ("LPS" for DICOM), if the format has one
    space: str | None = None
    #: several fields read as channels, [c, k, j, i] (`volren.io.channel_io`), `values` being the first
    channels: NDArray | None = None
    #: the channels' names and their numbers in the file's array
    channel_names: tuple[str, ...] = ()
    channel_indices: tuple[int, ...] = ()


@dataclass(frozen=True)
class Inspection:
    """What a header said: which reader to use, on what, and facts for the later steps."""

    reader: ReaderName
    target: Path
    layout: DataLayout | None = None
    facts: dict[str, Any] = field(default_factory=dict)


def _no_check(path: Path, view: DatasetView, result: ReadResult, inspection: Inspection) -> DatasetView:
    return view


def _no_adjust(grid: Grid, result: ReadResult, inspection: Inspection) -> Grid:
    return grid


@dataclass(frozen=True)
class FileFormat:
    """A file format volren reads: its suffixes and the three format-specific steps.

    `check_output` raises for what the reader got wrong without saying so, and returns the view,
    corrected where the reader misread something it could have read right. `read`, when given,
    replaces the VTK reader and those two steps: it returns the grid of one array, `array_name`,
    or None where the inspection leaves the file to the VTK reader.
    """

    name: str
    suffixes: tuple[str, ...]
    inspect: Callable[[Path], Inspection]
    check_output: Callable[[Path, DatasetView, ReadResult, Inspection], DatasetView] = _no_check
    adjust: Callable[[Grid, ReadResult, Inspection], Grid] = _no_adjust
    read: Callable[[Path, Inspection], Grid | None] | None = None
    array_name: str = ""


def read_head(path: Path, n: int = HEAD_BYTES) -> bytes:
    with open(path, "rb") as f:
        return f.read(n)


def quote(text: str | bytes, limit: int = 40) -> str:
    """A short, printable rendering of header text for messages (garbage stays one clean line)."""
    if isinstance(text, bytes):
        text = text.decode("latin-1")
    clean = "".join(c if c.isprintable() and ord(c) < 127 else "?" for c in text.strip())
    return repr(clean[:limit] + ("..." if len(clean) > limit else ""))


def is_identity(direction: NDArray | None) -> bool:
    return direction is None or bool(np.allclose(direction, np.eye(3), atol=1e-6))
