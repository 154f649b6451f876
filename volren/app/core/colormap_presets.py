"""Named colour maps for the 1D TF editor, as colour control points (no Qt).

Two sources, both data files beside this module, so the app needs no plotting library and no VTK:

- the curated maps, `colormap_presets.json`, written once by `scripts/make_colormap_presets.py`
  (the perceptually uniform maps at 16 stops, the piecewise-linear classics at their breakpoints,
  ParaView's "Cool to Warm" sampled from VTK at 17 stops; the script's docstring names the sources
  and their accuracies). They are the editor's combo box (`PRESET_NAMES`), read at import.
- ParaView's colour ramps, `paraview_colormaps.json`, imported by
  `scripts/import_paraview_colormaps.py` from ParaView's ColorMaps.json (BSD; the script says how
  and how accurately). They are for the preset browser, read the first time a name is asked for.

Names are unique across both: a ParaView map whose name is a curated one's (ignoring case, e.g.
"Viridis") is listed as "Viridis (ParaView)". A preset replaces the colours over the TF's current
value range and keeps the opacity.
"""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError
from volren.model.transfer_function import TransferFunction1D

DATA_FILE = Path(__file__).with_name("colormap_presets.json")
PARAVIEW_FILE = Path(__file__).with_name("paraview_colormaps.json")
#: Appended to a ParaView map's name that a curated map already has.
PARAVIEW_SUFFIX = " (ParaView)"


def _frozen(rows: list[list[float]]) -> NDArray[np.float64]:
    array = np.array(rows, dtype=np.float64)
    array.setflags(write=False)
    return array


@cache
def _presets() -> dict[str, NDArray[np.float64]]:
    data = json.loads(DATA_FILE.read_text(encoding="utf-8"))["presets"]
    return {name: _frozen(rows) for name, rows in data.items()}


#: The curated names in the order the editor lists them (the data file's order).
PRESET_NAMES: tuple[str, ...] = tuple(_presets())


@cache
def _paraview() -> dict[str, NDArray[np.float64]]:
    """ParaView's maps by their listed names (renamed where a curated map has the name)."""
    data = json.loads(PARAVIEW_FILE.read_text(encoding="utf-8"))
    curated = {name.casefold() for name in PRESET_NAMES}
    return {
        (name + PARAVIEW_SUFFIX if name.casefold() in curated else name): _frozen(rows)
        for name, rows in data.items()
    }


def paraview_names() -> tuple[str, ...]:
    """ParaView's colour ramps as listed, sorted by name (case ignored): easier to scan."""
    return tuple(sorted(_paraview(), key=str.casefold))


def all_preset_names() -> tuple[str, ...]:
    """Every colour map: the curated ones first (the editor's order), then ParaView's."""
    return PRESET_NAMES + paraview_names()


def preset_source(name: str) -> str:
    """Where a map comes from, for tooltips: "volren" (curated) or "ParaView"."""
    if name in _presets():
        return "volren"
    if name in _paraview():
        return "ParaView"
    raise VolrenError(f"no colour map named {name!r}")


def unit_stops(name: str) -> NDArray[np.float64]:
    """(k, 4) [x, r, g, b] with x from 0 to 1 (a copy)."""
    stops = _presets().get(name)
    if stops is None:
        stops = _paraview().get(name)
    if stops is None:
        raise VolrenError(
            f"no colour map named {name!r}; known: {', '.join(PRESET_NAMES)} and {len(_paraview())} "
            "of ParaView's (the colour-map browser lists them)"
        )
    return stops.copy()


def preset_color_points(name: str, lo: float, hi: float) -> NDArray[np.float64]:
    """The preset's stops spread over [lo, hi]: TransferFunction1D colour points."""
    stops = unit_stops(name)
    stops[:, 0] = lo + stops[:, 0] * (hi - lo)
    return stops


def apply_preset(tf: TransferFunction1D, name: str) -> None:
    """Give `tf` the preset's colours over its current value range; the opacity stays."""
    tf.set_color_points(preset_color_points(name, *tf.value_range))
