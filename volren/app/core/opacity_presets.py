"""Tissue presets for CT and MR (bone, soft tissue, lung, vessels; MR default, brain, angio): whole
1D TFs, colour and opacity, as 3D Slicer offers them (no Qt).

The presets are data, `opacity_presets.json` beside this module. CT presets are in Hounsfield
units and offered only where the data's values are HU (air near -1000: a CT preset on other data
would show nothing or everything); MR has no absolute scale, so MR presets are given over 0..1 and
spread over the data's 1st to 99.5th percentile (a few bright outliers must not squeeze the
preset). Opacities are per voxel length, as the default TF's. The editor's shift slider then
slides the whole preset along the value axis.
"""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from volren.errors import VolrenError
from volren.model.transfer_function import TransferFunction1D
from volren.model.value_histogram import value_histogram
from volren.model.volume import Volume

DATA_FILE = Path(__file__).with_name("opacity_presets.json")
#: Air is -1000 HU; scanners pad outside the field of view with -1024, -2048 or -3024.
AIR_HU = -1000.0
#: The percentiles of the data that an MR preset's 0 and 1 go to.
MR_PERCENTILES = (1.0, 99.5)


@cache
def _presets() -> dict[str, dict[str, Any]]:
    return json.loads(DATA_FILE.read_text(encoding="utf-8"))["presets"]


#: The names in the order the editor lists them (the data file's order).
OPACITY_PRESET_NAMES: tuple[str, ...] = tuple(_presets())


def is_hounsfield(volume: Volume) -> bool:
    """Whether the values look like CT Hounsfield units: air near -1000 (at or below -900, not
    below -3100), and nothing above what bone, contrast and metal reach (at most 32767, int16)."""
    lo, hi = volume.value_range
    return -3100.0 <= lo <= -900.0 and 100.0 <= hi <= 32767.0


def preset_problem(name: str, volume: Volume) -> str | None:
    """Why the preset `name` does not fit `volume` (None: it does)."""
    preset = _presets().get(name)
    if preset is None:
        raise VolrenError(f"no tissue preset named {name!r}; known: {', '.join(OPACITY_PRESET_NAMES)}")
    if preset["units"] == "HU" and not is_hounsfield(volume):
        lo, hi = volume.value_range
        return (f"CT presets are in Hounsfield units (air at {AIR_HU:g}); this data's values run from {lo:g} to "
                f"{hi:g}")  # fmt: skip
    return None


def robust_range(volume: Volume) -> tuple[float, float]:
    """The data's 1st and 99.5th percentiles, from its (cached) histogram: a bin's width accurate."""
    histogram = value_histogram(volume)
    cumulative = np.cumsum(histogram.counts)
    if cumulative[-1] == 0:
        return volume.value_range
    lo, hi = (
        float(np.interp(p / 100 * cumulative[-1], cumulative, histogram.edges[1:])) for p in MR_PERCENTILES
    )
    return (lo, hi) if hi > lo else volume.value_range


def preset_transfer_function(name: str, volume: Volume) -> TransferFunction1D:
    """The preset as a TF for `volume` (HU as they are; fractions over its robust range)."""
    problem = preset_problem(name, volume)
    if problem:
        raise VolrenError(f"{name}: {problem}")
    preset = _presets()[name]
    opacity = np.array(preset["opacity"], dtype=np.float64)
    color = np.array(preset["color"], dtype=np.float64)
    if preset["units"] == "fraction":
        lo, hi = robust_range(volume)
        for points in (opacity, color):
            points[:, 0] = lo + points[:, 0] * (hi - lo)
    return TransferFunction1D(color, opacity, volume.characteristic_length, {"preset": name})
