"""The value histogram: drawn behind the app's 1D TF editor, and what the default TF is made from.

Counts cover the volume's finite values over its value range: every voxel of a uniform grid, the
point values of a tetrahedral mesh. A histogram is computed once per volume object (and bin count)
and cached weakly, so switching TFs or toggling log counts never rescans the data, and a volume
that is closed frees its histogram with it.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass
from functools import partial

import numpy as np
from numpy.typing import NDArray

from volren.model.volume import Volume

#: Enough bars for a ~300 px wide editor without aliasing; bars merge on narrower ones.
DEFAULT_BINS = 256
#: Values per chunk of the float path: bounds the float64 copy to ~32 MiB at a time.
_CHUNK = 1 << 22
#: Values per bincount of the integer path: its intp copy (8 MiB) stays in cache. On bonsai's 16.7 M
#: 8-bit values one bincount of them all took 0.33 s, 1 M-value chunks 0.03 s.
_TALLY_CHUNK = 1 << 20

_cache: weakref.WeakKeyDictionary[Volume, dict[int, Histogram]] = weakref.WeakKeyDictionary()


@dataclass(frozen=True, eq=False)
class Histogram:
    """Counts of values in equal-width bins: `edges` (bins + 1,), `counts` (bins,) int64 (or
    float volumes, `volren.model.default_tf.volume_histogram`)."""

    edges: NDArray[np.float64]
    counts: NDArray[np.int64]

    def heights(self, log: bool = False) -> NDArray[np.float64]:
        """Bar heights in [0, 1], the fullest bin at 1.

        `log` scales by log(1 + count), so bins with a handful of values (thin structures such as
        vessels next to a large background peak) stay visible, and empty bins stay at 0.
        """
        counts = self.counts.astype(np.float64)
        top = counts.max(initial=0.0)
        if top <= 0:
            return np.zeros_like(counts)
        if log:
            return np.log1p(counts) / np.log1p(top)
        return counts / top


def value_histogram(volume: Volume, bins: int = DEFAULT_BINS) -> Histogram:
    """The histogram of `volume`'s finite values over `volume.value_range` (cached per volume)."""
    if bins < 1:
        raise ValueError(f"a histogram needs at least one bin, got {bins}")
    per_volume = _cache.setdefault(volume, {})
    found = per_volume.get(bins)
    if found is None:
        found = per_volume[bins] = compute_histogram(volume.values, bins, volume.value_range)
    return found


def cached_value_histogram(volume: Volume, bins: int = DEFAULT_BINS) -> Histogram | None:
    """`value_histogram(volume, bins)` when it was computed before, else None (no work)."""
    return _cache.get(volume, {}).get(bins)


def compute_histogram(values: NDArray, bins: int, value_range: tuple[float, float]) -> Histogram:
    """np.histogram's bins and counts for the finite `values`, faster for 8- and 16-bit integers."""
    lo, hi = float(value_range[0]), float(value_range[1])
    flat = np.asarray(values).reshape(-1)
    if np.issubdtype(flat.dtype, np.integer) and flat.dtype.itemsize <= 2 and flat.size:
        counts, edges = _integer_histogram(flat, bins, lo, hi)
    else:
        counts, edges = _float64_histogram(flat, bins, lo, hi)
    return Histogram(edges.astype(np.float64), counts.astype(np.int64))


def _float64_histogram(flat: NDArray, bins: int, lo: float, hi: float) -> tuple[NDArray, NDArray]:
    """np.histogram of the finite values in float64, a chunk at a time: in float32 the distance
    of a value near 3.4e38 from the range's start overflows (and its bin index with it). A span
    beyond float64's own range (-1e308 to 1e308) is binned halved, which is exact."""
    scale = 1.0 if math.isfinite(hi - lo) else 0.5
    span = (lo * scale, hi * scale)
    counts = np.zeros(bins, np.int64)
    for start in range(0, flat.size, _CHUNK):
        chunk = flat[start : start + _CHUNK].astype(np.float64)
        chunk = chunk[np.isfinite(chunk)] * scale
        counts += np.histogram(chunk, bins, span)[0]
    return counts, np.histogram_bin_edges(np.empty(0), bins, span) / scale


def _byte_tally(chunk: NDArray[np.uint8]) -> NDArray[np.int64]:
    """np.bincount of bytes, two at a time: the bytes read as 16-bit pairs (half the elements, and
    np.bincount widens each to 64 bits) tally 65,536 pairs, whose rows and columns sum to the tally
    of the high and the low byte; about 2x quicker."""
    even = chunk.size - chunk.size % 2
    pairs = np.bincount(chunk[:even].view(np.uint16), minlength=1 << 16).reshape(256, 256)
    tally = pairs.sum(axis=0) + pairs.sum(axis=1)
    if even < chunk.size:
        tally[chunk[-1]] += 1
    return tally


def _integer_histogram(flat: NDArray, bins: int, lo: float, hi: float) -> tuple[NDArray, NDArray]:
    """Tally each of the type's levels (a bincount of the values read as unsigned, ~10x faster than
    np.histogram on CT data), then bin the levels in [lo, hi] weighted by their tallies: the same
    bin for every value as np.histogram gives, and values outside [lo, hi] left out as it does."""
    bits = 8 * flat.dtype.itemsize
    unsigned = flat.view(np.dtype(f"u{flat.dtype.itemsize}"))
    tally = np.zeros(1 << bits, np.int64)
    count = _byte_tally if bits == 8 else partial(np.bincount, minlength=tally.size)
    for start in range(0, flat.size, _TALLY_CHUNK):
        tally += count(np.ascontiguousarray(unsigned[start : start + _TALLY_CHUNK]))
    offset = 0
    if np.issubdtype(flat.dtype, np.signedinteger):  # two's complement: level i - offset at index i
        offset = 1 << (bits - 1)
        tally = np.roll(tally, offset)
    first = max(int(np.floor(lo)) + offset, 0)
    last = min(int(np.ceil(hi)) + offset, tally.size - 1)
    levels = np.arange(first, last + 1, dtype=np.float64) - offset
    counts, edges = np.histogram(levels, bins, (lo, hi), weights=tally[first : last + 1])
    return np.rint(counts).astype(np.int64), edges
