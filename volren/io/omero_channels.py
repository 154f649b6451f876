"""OME-Zarr's ``omero.channels``: how a fluorescence image's channels are shown at first.

Each entry (OME-NGFF 0.4, "omero" metadata, transitional) may give a ``label`` (the channel's name),
a ``color`` ("RRGGBB" hex), a ``window`` ({"start", "end", "min", "max"}: the values mapped from
dark to full colour) and ``active`` (shown or not). Entries that are missing or malformed fall back
to volren's defaults (a name "channel N", the palette's colour, the value range, shown): viewers
write this metadata loosely, and a wrong hint must not stop an image from being drawn.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class ChannelHint:
    """One channel's display hints (None: not given, or not usable)."""

    name: str | None = None
    color: tuple[float, float, float] | None = None
    window: tuple[float, float] | None = None
    active: bool = True


def parse_color(text: Any) -> tuple[float, float, float] | None:
    """An "RRGGBB" hex colour (a leading "#" allowed) as floats in [0, 1]; None if malformed."""
    if not isinstance(text, str):
        return None
    digits = text.strip().removeprefix("#")
    if len(digits) != 6:
        return None
    try:
        r, g, b = (int(digits[i : i + 2], 16) for i in (0, 2, 4))
    except ValueError:
        return None
    return (r / 255.0, g / 255.0, b / 255.0)


def parse_window(window: Any) -> tuple[float, float] | None:
    """(start, end) of an omero window when both are finite numbers and end > start."""
    if not isinstance(window, Mapping):
        return None
    ends = [window.get("start"), window.get("end")]
    if not all(isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in ends):
        return None
    start, end = float(ends[0]), float(ends[1])  # type: ignore[arg-type]
    return (start, end) if end > start else None


def channel_hints(omero: Mapping[str, Any] | None, count: int) -> list[ChannelHint]:
    """The hints of each of `count` channels from the "omero" attributes (defaults where absent)."""
    listed = omero.get("channels") if isinstance(omero, Mapping) else None
    entries = listed if isinstance(listed, list) and len(listed) == count else [None] * count
    hints = []
    for entry in entries:
        if not isinstance(entry, Mapping):
            hints.append(ChannelHint())
            continue
        label = entry.get("label")
        active = entry.get("active", True)
        hints.append(ChannelHint(str(label) if isinstance(label, str | int) and str(label) else None,
                                 parse_color(entry.get("color")), parse_window(entry.get("window")),
                                 active if isinstance(active, bool) else True))  # fmt: skip
    return hints
