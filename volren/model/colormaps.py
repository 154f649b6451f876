"""Colour maps as transfer-function colour stops (x in [0, 1], r, g, b), scaled onto a range."""

from __future__ import annotations

import math

#: Viridis (van der Walt and Smith's perceptually uniform, colour-blind safe map) at five evenly spaced stops.
VIRIDIS = (
    (0.0, 0.267, 0.005, 0.329),
    (0.25, 0.230, 0.322, 0.546),
    (0.5, 0.128, 0.567, 0.551),
    (0.75, 0.369, 0.789, 0.383),
    (1.0, 0.993, 0.906, 0.144),
)


def lerp(lo: float, hi: float, x: float) -> float:
    """lo + x (hi - lo), finite even where hi - lo overflows (data near the float64 limits, whose
    default TF would otherwise get infinite control points)."""
    if x == 1.0:  # exactly the end, as lo + 1 * (hi - lo) need not be
        return hi
    span = hi - lo
    if math.isfinite(span):
        return lo + x * span
    return lo * (1.0 - x) + hi * x


def color_stops(stops, lo: float, hi: float) -> list[list[float]]:
    """The stops with x mapped from [0, 1] onto [lo, hi]: TransferFunction1D colour points."""
    return [[lerp(lo, hi, x), r, g, b] for x, r, g, b in stops]
