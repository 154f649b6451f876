"""What a volume looks like before anyone edits its TF, derived from its value histogram.

Two failures of a fixed ramp: CT data, where air fills most of the volume at the bottom
of the range, turned into fog; and flow meshes, where the fast outer flow fills most of the domain
at the top of the range, hid the wake behind an opaque shell. So:

The histogram counts volume, not samples: a mesh's points are weighted by the volume of their
tetrahedra (a quarter of each), since meshes are refined where the flow is interesting and the
point count says little about how much of a ray a value fills.

- A **background**, a tenth of the value range holding at least `BACKGROUND_SHARE` of the
  volume (air, MR noise, a free stream), is made transparent with the bins beside it that stay
  dense: everything up to its end when it sits in the lower half of the range, everything from its
  start up when it sits in the upper half. Without one, the bottom tenth is transparent.
- The rest of the range ramps linearly to `peak` opacity, and `peak` is chosen so that an average
  ray through the volume's middle has optical depth `TARGET_DEPTH` (transmits e^-2, 14 %): the
  mean extinction over all values, times the samples across the volume, is that depth. Dense data
  gets faint opacities, sparse data (thin vessels) strong ones, at most `MAX_PEAK`.

Colours are viridis over the visible part. A constant field is a translucent box (opacity 0.3),
the same in every renderer.
"""

from __future__ import annotations

import math
from typing import cast

import numpy as np
from numpy.typing import NDArray

from volren.model.colormaps import VIRIDIS, color_stops, lerp
from volren.model.transfer_function import TransferFunction1D
from volren.model.value_histogram import DEFAULT_BINS, Histogram, value_histogram
from volren.model.volume import TetVolume, Volume

#: A tenth of the value range holding this share of the volume is background.
WINDOW, BACKGROUND_SHARE = 0.1, 0.4
#: Where a background ends: bins below this fraction of its mean density.
PEAK_EDGE = 1 / 4
#: The optical depth of an average ray through the middle of the volume.
TARGET_DEPTH = 2.0
MIN_PEAK, MAX_PEAK = 0.002, 0.9
CONSTANT_OPACITY = 0.3


def _background(counts: NDArray) -> tuple[int, int] | None:
    """The bins (first, last) of the background: the densest tenth of the range, when it holds a
    background's share, widened over the bins beside it that stay at a quarter of its density."""
    total = float(counts.sum())
    width = max(1, round(WINDOW * len(counts)))
    mass = np.convolve(counts, np.ones(width), mode="valid")
    start = int(np.argmax(mass))
    if total <= 0 or mass[start] < BACKGROUND_SHARE * total:
        return None
    dense = counts >= PEAK_EDGE * mass[start] / width
    first, last = start, start + width - 1
    while first > 0 and dense[first - 1]:
        first -= 1
    while last < len(counts) - 1 and dense[last + 1]:
        last += 1
    return first, last


def _shape(volume: Volume, edges: NDArray, counts: NDArray) -> tuple[list[list[float]], float, float]:
    """Opacity points with a peak of 1, and the (lo, hi) of the visible part."""
    lo, hi = volume.value_range
    peak = _background(counts)
    if peak is None:
        start = lerp(lo, hi, 0.1)
        return [[lo, 0.0], [start, 0.0], [hi, 1.0]], start, hi
    first, last = peak
    if (first + last + 1) / 2 <= len(counts) / 2:  # a background at the bottom (air, noise)
        start = float(edges[last + 1])
        if start >= hi:
            start = lerp(lo, hi, 0.1)
        return [[lo, 0.0], [start, 0.0], [hi, 1.0]], start, hi
    end = float(edges[first])  # a background at the top (a free stream): it is what hides the rest
    begin = lerp(lo, end, 0.1)
    if end <= begin:
        return [[lo, 0.0], [lerp(lo, hi, 0.1), 0.0], [hi, 1.0]], lerp(lo, hi, 0.1), hi
    return [[lo, 0.0], [begin, 0.0], [end, 1.0], [end, 0.0], [hi, 0.0]], begin, end


def _peak_opacity(volume: Volume, shape: list[list[float]], edges: NDArray, counts: NDArray) -> float:
    """The peak whose mean extinction over the histogram, times the samples across the volume,
    is TARGET_DEPTH (bisection: the depth grows with the peak)."""
    b = volume.bounds
    samples = cast(float, np.mean([b[1] - b[0], b[3] - b[2], b[5] - b[4]])) / volume.characteristic_length
    centres = 0.5 * (edges[:-1] + edges[1:])
    xs, ys = np.array(shape).T
    weights = counts / max(counts.sum(), 1)
    relative = np.interp(centres, xs, ys)

    def depth(peak: float) -> float:
        return samples * float(weights @ -np.log1p(-np.minimum(peak * relative, 1 - 1e-6)))

    low, high = MIN_PEAK, MAX_PEAK
    if depth(high) <= TARGET_DEPTH:
        return high
    if depth(low) >= TARGET_DEPTH:
        return low
    for _ in range(50):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if depth(middle) < TARGET_DEPTH else (low, middle)
    return 0.5 * (low + high)


def volume_histogram(volume: Volume) -> Histogram:
    """The value histogram by volume: voxels as they are, a mesh's points by a quarter of the
    volume of each tetrahedron they are a corner of."""
    if not isinstance(volume, TetVolume):
        return value_histogram(volume)
    points, tets = volume.points, volume.tets
    first = points[tets[:, 0]]
    a, b, c = (points[tets[:, k]] - first for k in (1, 2, 3))
    # the triple product a . (b x c) by components: np.cross and a (m, 4, 3) gather of the corners
    # took 4x as long on 513k cells
    det = (a[:, 0] * (b[:, 1] * c[:, 2] - b[:, 2] * c[:, 1]) - a[:, 1] * (b[:, 0] * c[:, 2] - b[:, 2] * c[:, 0])
           + a[:, 2] * (b[:, 0] * c[:, 1] - b[:, 1] * c[:, 0]))  # fmt: skip
    weights = np.bincount(tets.reshape(-1), np.repeat(np.abs(det) / 24, 4), minlength=len(points))
    values = volume.values.astype(np.float64)
    finite = np.isfinite(values)
    counts, bin_edges = np.histogram(
        values[finite], DEFAULT_BINS, volume.value_range, weights=weights[finite]
    )
    return Histogram(bin_edges, counts)


def default_transfer_function(volume: Volume) -> TransferFunction1D:
    """The TF a volume gets when none is given (see the module docstring), per voxel (or tet edge)."""
    lo, hi = volume.value_range
    if not math.isfinite(hi - lo):  # values near the float64 limits: no histogram has finite bins there
        color, opacity = (
            color_stops(VIRIDIS, lo, hi),
            [[lo, 0.0], [lerp(lo, hi, 0.1), 0.0], [hi, CONSTANT_OPACITY]],
        )
        return TransferFunction1D(color, opacity, volume.characteristic_length)
    if not hi > lo:
        return TransferFunction1D(color_stops(VIRIDIS, lo, lo + 1.0), [[lo, CONSTANT_OPACITY], [lo + 1.0, CONSTANT_OPACITY]],
                                  volume.characteristic_length)  # fmt: skip
    histogram = volume_histogram(volume)
    shape, visible_lo, visible_hi = _shape(volume, histogram.edges, histogram.counts)
    peak = _peak_opacity(volume, shape, histogram.edges, histogram.counts)
    opacity = [[x, a * peak] for x, a in shape]
    return TransferFunction1D(
        color_stops(VIRIDIS, visible_lo, visible_hi), opacity, volume.characteristic_length
    )
