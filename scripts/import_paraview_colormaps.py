"""Write volren/app/core/paraview_colormaps.json: ParaView's colour maps as [x, r, g, b] stops.

Source: ParaView's colour-map presets, `Remoting/Views/ColorMaps.json` in the ParaView repository
(https://github.com/Kitware/ParaView), Copyright (c) 2000 Kitware Inc., distributed under ParaView's
BSD 3-clause licence (its `Copyright.txt`). Some maps carry their own provenance in that file
(the matplotlib maps Viridis, Plasma, Inferno, Magma are CC0, Cividis likewise; Francesca Samsel's
and others name their creators); those fields are not copied, the names are.

Re-run from the repository root when ParaView's presets change; it needs VTK (volren's io extra),
the app that reads the data file does not:

    git show HEAD:Remoting/Views/ColorMaps.json > ColorMaps.json   # in a ParaView checkout
    python scripts/import_paraview_colormaps.py ColorMaps.json [OUT.json]

What is kept: every preset with "RGBPoints" and without "IndexedColors" (categorical maps are not
colour ramps), in ParaView's order. Presets interpolate in their ColorSpace (Lab, Diverging,
HSV, Step, ...), not in RGB, so each one goes through `volren.io.paraview_presets.preset_to_tf`,
which samples VTK's own interpolation into piecewise-linear RGB (within 2e-4); that is then
simplified back to the fewest stops within `TOLERANCE` (half an 8-bit level: the same colours on
screen, fewer markers on the colour bar), x is normalised to [0, 1], and every number is rounded to
`DIGITS` decimals. The file has no whitespace: it is data, read once when the preset browser opens.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from volren.io.json_text import read_json
from volren.io.paraview_presets import is_preset_data, preset_to_tf, simplify_polyline

OUT = Path(__file__).resolve().parents[1] / "volren" / "app" / "core" / "paraview_colormaps.json"
#: Largest colour error (any channel) the simplified stops may have against VTK's interpolation.
TOLERANCE = 1.0 / 512
#: Decimals kept for x and for each channel.
DIGITS = 4


def wanted(preset: Mapping[str, Any]) -> bool:
    """A colour ramp: RGBPoints, no IndexedColors, and a name to list it by."""
    return "RGBPoints" in preset and "IndexedColors" not in preset and isinstance(preset.get("Name"), str)


def unit_stops(preset: Mapping[str, Any], source: Path) -> NDArray[np.float64]:
    """The preset's colours as (k, 4) [x, r, g, b] stops, x from 0 to 1, rounded to DIGITS."""
    colors = preset_to_tf(preset, source).color_points
    colors = colors[simplify_polyline(colors[:, 0], colors[:, 1:], TOLERANCE)]
    lo, hi = colors[0, 0], colors[-1, 0]
    colors[:, 0] = (colors[:, 0] - lo) / (hi - lo) if hi > lo else np.linspace(0.0, 1.0, len(colors))
    colors = np.round(colors, DIGITS)
    colors[[0, -1], 0] = 0.0, 1.0
    return colors


def convert(presets: Sequence[Mapping[str, Any]], source: Path) -> dict[str, list[list[float]]]:
    """Name -> stops for every wanted preset, in ParaView's order (the first of a repeated name)."""
    maps: dict[str, list[list[float]]] = {}
    for preset in presets:
        if wanted(preset) and preset["Name"] not in maps:
            maps[preset["Name"]] = unit_stops(preset, source).tolist()
    return maps


def _number(v: float) -> str:
    """1.0 -> "1", 0.25 -> "0.25": the shortest text of a rounded number."""
    return str(int(v)) if v == int(v) else repr(v)


def document(maps: Mapping[str, list[list[float]]]) -> str:
    """The data file's text: one JSON object, no whitespace."""
    items = (
        json.dumps(name)
        + ":["
        + ",".join("[" + ",".join(_number(v) for v in row) + "]" for row in stops)
        + "]"
        for name, stops in maps.items()
    )
    return "{" + ",".join(items) + "}"


def main(argv: list[str]) -> int:
    if not argv or len(argv) > 2:
        print("usage: python scripts/import_paraview_colormaps.py ColorMaps.json [OUT.json]", file=sys.stderr)
        return 2
    source = Path(argv[0])
    out = Path(argv[1]) if len(argv) > 1 else OUT
    data = read_json(source)  # ParaView's file has trailing commas; read_json allows them
    if not is_preset_data(data):
        print(f"{source}: not a ParaView preset file", file=sys.stderr)
        return 1
    maps = convert(data if isinstance(data, list) else [data], source)
    out.write_text(document(maps), encoding="utf-8")
    print(f"wrote {len(maps)} colour maps to {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
