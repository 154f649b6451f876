"""Named colour maps for the 1D TF editor, as colour control points (no Qt).

Few stops keep the colour bar editable: matplotlib's perceptually uniform maps are smooth, and 16
evenly spaced stops follow their 256-entry tables within 0.04 in any channel (cividis's dark end;
viridis 0.026). The classics are piecewise linear in RGB and are given by their exact breakpoints:
matplotlib's segment data for "Jet" and "Bone", ParaView's nodes for "Grayscale" and "Black-Body
Radiation". ParaView's default "Cool to Warm" interpolates in Moreland's diverging (Msh) space,
which is not linear in RGB: the ParaView preset reader samples VTK's own interpolation, and 17
evenly spaced stops of that (white exactly in the middle) stay within 0.035 of ParaView's colours.

A preset replaces the colours over the TF's current value range and keeps the opacity.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from functools import cache
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError
from volren.model.transfer_function import TransferFunction1D

#: Stops per matplotlib perceptual map.
MATPLOTLIB_STOPS = 16
MATPLOTLIB_MAPS = ("viridis", "plasma", "inferno", "magma", "cividis")
#: Odd, so that the diverging map's white midpoint is a stop.
COOL_TO_WARM_STOPS = 17

#: (x, y) segments per channel, as in matplotlib's `_cm` segment data.
Segments = Sequence[tuple[float, float]]

_JET = (
    ((0.0, 0.0), (0.35, 0.0), (0.66, 1.0), (0.89, 1.0), (1.0, 0.5)),
    ((0.0, 0.0), (0.125, 0.0), (0.375, 1.0), (0.64, 1.0), (0.91, 0.0), (1.0, 0.0)),
    ((0.0, 0.5), (0.11, 1.0), (0.34, 1.0), (0.65, 0.0), (1.0, 0.0)),
)
_BONE = (
    ((0.0, 0.0), (0.746032, 0.652778), (1.0, 1.0)),
    ((0.0, 0.0), (0.365079, 0.319444), (0.746032, 0.777778), (1.0, 1.0)),
    ((0.0, 0.0), (0.365079, 0.444444), (1.0, 1.0)),
)
_GRAYSCALE = ((0.0, 0.0, 0.0, 0.0), (1.0, 1.0, 1.0, 1.0))
_BLACK_BODY = (
    (0.0, 0.0, 0.0, 0.0),
    (0.4, 0.901960784314, 0.0, 0.0),
    (0.8, 0.901960784314, 0.901960784314, 0.0),
    (1.0, 1.0, 1.0, 1.0),
)
#: ParaView's default colour map (Moreland 2009), as in ParaView's ColorMaps.json.
COOL_TO_WARM_PRESET = {
    "Name": "Cool to Warm",
    "ColorSpace": "Diverging",
    "RGBPoints": [
        0.0, 0.23137254902, 0.298039215686, 0.752941176471,
        0.5, 0.865, 0.865, 0.865,
        1.0, 0.705882352941, 0.0156862745098, 0.149019607843,
    ],
}  # fmt: skip


def _matplotlib(name: str) -> NDArray[np.float64]:
    from matplotlib import colormaps

    x = np.linspace(0.0, 1.0, MATPLOTLIB_STOPS)
    return np.column_stack([x, colormaps[name](x)[:, :3]])


def _segments(channels: tuple[Segments, Segments, Segments]) -> NDArray[np.float64]:
    """Stops at every breakpoint of any channel: exact for maps linear between breakpoints."""
    x = np.unique(np.concatenate([[p[0] for p in channel] for channel in channels]))
    rgb = [np.interp(x, [p[0] for p in channel], [p[1] for p in channel]) for channel in channels]
    return np.column_stack([x, *rgb])


def _cool_to_warm() -> NDArray[np.float64]:
    from volren.io.paraview_presets import preset_to_tf

    fine = preset_to_tf(COOL_TO_WARM_PRESET, Path("Cool to Warm")).color_points
    x = np.linspace(fine[0, 0], fine[-1, 0], COOL_TO_WARM_STOPS)
    return np.column_stack([x, *(np.interp(x, fine[:, 0], fine[:, c]) for c in (1, 2, 3))])


_BUILDERS: dict[str, Callable[[], NDArray[np.float64]]] = {
    **{name: (lambda name=name: _matplotlib(name)) for name in MATPLOTLIB_MAPS},
    "Cool to Warm": _cool_to_warm,
    "Black-Body Radiation": lambda: np.array(_BLACK_BODY),
    "Grayscale": lambda: np.array(_GRAYSCALE),
    "Jet": lambda: _segments(_JET),
    "Bone": lambda: _segments(_BONE),
}

#: The names in the order the editor lists them.
PRESET_NAMES: tuple[str, ...] = tuple(_BUILDERS)


@cache
def _unit_stops(name: str) -> NDArray[np.float64]:
    if name not in _BUILDERS:
        raise VolrenError(f"no colour map named {name!r}; known: {', '.join(PRESET_NAMES)}")
    stops = np.asarray(_BUILDERS[name](), dtype=np.float64)
    lo, hi = stops[0, 0], stops[-1, 0]
    stops[:, 0] = (stops[:, 0] - lo) / (hi - lo)
    stops[:, 1:] = np.clip(stops[:, 1:], 0.0, 1.0)
    stops.setflags(write=False)
    return stops


def unit_stops(name: str) -> NDArray[np.float64]:
    """(k, 4) [x, r, g, b] with x from 0 to 1 (built once per name; a copy)."""
    return _unit_stops(name).copy()


def preset_color_points(name: str, lo: float, hi: float) -> NDArray[np.float64]:
    """The preset's stops spread over [lo, hi]: TransferFunction1D colour points."""
    stops = unit_stops(name)
    stops[:, 0] = lo + stops[:, 0] * (hi - lo)
    return stops


def apply_preset(tf: TransferFunction1D, name: str) -> None:
    """Give `tf` the preset's colours over its current value range; the opacity stays."""
    tf.set_color_points(preset_color_points(name, *tf.value_range))
