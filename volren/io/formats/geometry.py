"""One rule for the grid geometry a header declares, whichever format declares it.

Why: VTK's readers each do something else with a bad spacing or origin: the XML reader puts back
1 and 0 for NaN, the MetaImage reader turns NaN into 0 and drops a negative sign without flipping
the data, and NRRD spacings were replaced by 1. Here the header's own numbers are checked, in
every format, before VTK reads the file:

- spacing: three finite, non-zero numbers, else the file is refused (one line naming the field);
- origin: three finite numbers, else refused;
- a negative spacing mirrors its axis: the grid's samples run the other way. It is kept negative
  (`signed_as_declared` puts back a sign the reader dropped) and `dataset.volume_from_grid` flips
  the values so the model's spacing is positive and every sample stays where the header put it.
"""

from __future__ import annotations

import math
from pathlib import Path

from volren.errors import file_error
from volren.io.formats.base import Grid

Triple = tuple[float, float, float]


def parse_numbers(path: Path, field: str, text: str | None, count: int = 3) -> Triple | None:
    """The first `count` numbers of a header field (NaN and Inf included), None when it is absent."""
    if text is None or not text.strip():
        return None
    words = text.replace(",", " ").replace("(", " ").replace(")", " ").split()
    try:
        values = tuple(float(w) for w in words[:count])
    except ValueError:
        raise file_error(path, f"{field} {text.strip()!r} must be {count} numbers") from None
    if len(values) < count:
        raise file_error(path, f"{field} {text.strip()!r} must be {count} numbers")
    return values  # type: ignore[return-value]


def check_declared(
    path: Path,
    spacing: Triple | None,
    origin: Triple | None,
    spacing_field: str = "spacing",
    origin_field: str = "origin",
) -> dict[str, Triple]:
    """The facts to keep ({'declared_spacing': ..}); a one-line error for a value no grid can have."""
    facts: dict[str, Triple] = {}
    if spacing is not None:
        shown = " ".join(f"{v:g}" for v in spacing)
        if not all(math.isfinite(v) for v in spacing):
            raise file_error(path, f"{spacing_field} {shown} must be finite numbers")
        if any(v == 0 for v in spacing):
            raise file_error(path, f"{spacing_field} {shown} has a zero entry: the samples would coincide")
        facts["declared_spacing"] = spacing
    if origin is not None and not all(math.isfinite(v) for v in origin):
        raise file_error(path, f"{origin_field} {' '.join(f'{v:g}' for v in origin)} must be finite numbers")
    return facts


def signed_as_declared(grid: Grid, declared: Triple | None) -> Grid:
    """The grid with the header's negative spacings back where the reader made them positive."""
    if declared is None:
        return grid
    spacing = tuple(-abs(s) if d < 0 else s for s, d in zip(grid.spacing, declared))
    if spacing == tuple(grid.spacing):
        return grid
    grid.spacing = spacing  # type: ignore[assignment]
    return grid
