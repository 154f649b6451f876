"""Named colour maps for the 1D TF editor, as colour control points (no Qt).

The stops are data, `colormap_presets.json` beside this module, written once by
`scripts/make_colormap_presets.py` from their sources (the perceptually uniform maps at 16 stops,
the piecewise-linear classics at their breakpoints, ParaView's "Cool to Warm" sampled from VTK at
17 stops; the script's docstring names the sources and their accuracies). So the app needs no
plotting library and no VTK for them, and opening the list costs one small file read.

A preset replaces the colours over the TF's current value range and keeps the opacity.
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


@cache
def _presets() -> dict[str, NDArray[np.float64]]:
    data = json.loads(DATA_FILE.read_text(encoding="utf-8"))["presets"]
    stops = {name: np.array(rows, dtype=np.float64) for name, rows in data.items()}
    for array in stops.values():
        array.setflags(write=False)
    return stops


#: The names in the order the editor lists them (the data file's order).
PRESET_NAMES: tuple[str, ...] = tuple(_presets())


def unit_stops(name: str) -> NDArray[np.float64]:
    """(k, 4) [x, r, g, b] with x from 0 to 1 (a copy)."""
    stops = _presets().get(name)
    if stops is None:
        raise VolrenError(f"no colour map named {name!r}; known: {', '.join(PRESET_NAMES)}")
    return stops.copy()


def preset_color_points(name: str, lo: float, hi: float) -> NDArray[np.float64]:
    """The preset's stops spread over [lo, hi]: TransferFunction1D colour points."""
    stops = unit_stops(name)
    stops[:, 0] = lo + stops[:, 0] * (hi - lo)
    return stops


def apply_preset(tf: TransferFunction1D, name: str) -> None:
    """Give `tf` the preset's colours over its current value range; the opacity stays."""
    tf.set_color_points(preset_color_points(name, *tf.value_range))
