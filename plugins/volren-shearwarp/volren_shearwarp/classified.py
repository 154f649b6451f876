"""The classified volume: one slice-ordered copy of the values per principal axis, and per copy
the runs of cells that the transfer function may make visible.

Why: shear-warp walks slices in order, so each principal axis needs the volume laid out slice by
slice with scanlines contiguous (three copies, built lazily; uint8 data as it is, anything else
float32, so NaN survives). Empty
space is skipped by run-length encoding (Lacroute and Levoy 1994): per slab (two adjacent
slices) and per cell row, the runs of cells where something may show.

When a cell is transparent, for pre-integration: a slab's segment runs linearly from a front
value (bilinear in one slice) to a back value (bilinear in the slab's other slice: the next, or
`stride` slices on when the renderer composites every stride-th slice), so its colour is zero only
when the TF opacity is zero on the whole interval between them. A ray whose front point lies in
cell (a, b) has its back point within e = ceil(stride x largest shear) cells of it, and on the side
the ray moves to: cells a .. a + e along a where it moves towards larger a (a - e .. a where it
moves back), the same along b. Every value it can meet therefore lies between the min and the max
of the vertices, in the slab's two slices, of one block of (e + 1) x (e + 1) cells anchored on that
side. The runs are over those *anchored* blocks (`_block_ranges`: block j along an axis is cells
j - e .. j, so the ray moving forward takes block a + e and one moving back block a); the renderer
knows each ray's direction per frame (the shift along b is fixed per intermediate row, the one
along a changes sign at most once per row), and picks the block. Why not a block centred on the
cell, (2e + 1)^2 cells, which needs no direction: it composited 1.2-2.5x as many segments on the
shared scenes (docs/shearwarp.md). A block is skipped only when the
opacity is zero on all of [min, max]: the interval, not the union of its cells' ranges, since a
segment between two values passes through everything in between. Cells with a NaN corner are
transparent (DESIGN.md) and add nothing to the range.

The test reads the TF only through which value bins have nonzero opacity (`OpacitySupport`):
colour edits, and opacity edits that keep the support, reuse the runs.
Each block's value range does not depend on the TF: it is computed once per axis copy and kept as
two bytes per cell (`AxisCopy.ranges`, half the copy's size), so an opacity edit that changes the
support only compares ranges with it and re-extracts the runs.
"""

from __future__ import annotations

import hashlib
import math
import time
from dataclasses import dataclass, field

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from volren.model import TransferFunction1D, UniformVolume
from volren.model.volume import spanning
from volren_shearwarp.factorization import PERMS

#: Value bins of the opacity support over the volume's value range.
SUPPORT_BINS = 4096
#: Gaps between runs shorter than this many cells are bridged: the compositing kernel pays more
#: per run (its pixel bounds) than for a few transparent cells.
MIN_GAP = 3


@dataclass(frozen=True)
class OpacitySupport:
    """Which of `SUPPORT_BINS` equal bins of [lo, hi] hold a value with nonzero TF opacity, as a
    prefix count (`counts[i]` = nonzero bins before bin i), and a digest that keys the runs."""

    lo: float
    hi: float
    counts: NDArray[np.int32]
    digest: str

    @classmethod
    def of(cls, tf: TransferFunction1D, lo: float, hi: float, bins: int = SUPPORT_BINS) -> OpacitySupport:
        """The support of `tf` over [lo, hi]: exact for piecewise-linear opacity (a bin is nonzero when
        the opacity is nonzero at either end or at a control point inside it)."""
        lo, hi = spanning(lo, hi)
        edges = np.linspace(lo, hi, bins + 1)
        points = tf.opacity_points
        _, at_edges = tf.sample(edges)
        nonzero = (at_edges[:-1] > 0) | (at_edges[1:] > 0)
        inside = (points[:, 0] > lo) & (points[:, 0] < hi) & (points[:, 1] > 0)
        if inside.any():
            which = np.clip(((points[inside, 0] - lo) / (hi - lo) * bins).astype(np.int64), 0, bins - 1)
            nonzero[which] = True
        counts = np.zeros(bins + 1, np.int32)
        np.cumsum(nonzero, out=counts[1:])
        digest = hashlib.sha256(np.packbits(nonzero).tobytes() + np.array([lo, hi]).tobytes()).hexdigest()
        return cls(float(lo), float(hi), counts, digest)

    @property
    def empty(self) -> bool:
        return int(self.counts[-1]) == 0


def slab_pairs(order: NDArray[np.int64]) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """The slabs of a compositing order (slice indices front to back, every slice or every
    stride-th): their (lower, upper) slices sorted by lower slice, and for m >= 1 the index in that
    list of the slab between order[m - 1] and order[m] (entry 0 unused, -1). Why sorted: the runs of
    an every-slice order are then the same whichever way the order runs."""
    lower = np.minimum(order[:-1], order[1:])
    upper = np.maximum(order[:-1], order[1:])
    rank = np.argsort(lower, kind="stable")
    pairs = np.ascontiguousarray(np.stack([lower[rank], upper[rank]], axis=1).astype(np.int64))
    run_slab = np.full(len(order), -1, np.int64)
    run_slab[1 + rank] = np.arange(len(rank))
    return pairs, run_slab


#: Types the axis copies keep as they are (every value exact in float32, where the kernels convert it).
#: Why uint8 only: each kept type is one more compilation of the volume kernels at set-up (`volren
#: prepare`: about 70 s each on this machine's fast days, so int16 and uint16 too took CI from 8 to 12
#: minutes); 8-bit data gains the most (4x less memory against 2x).
KEPT_COPY_DTYPES = (np.dtype(np.uint8),)


def copy_dtype(dtype: np.dtype) -> np.dtype:
    """The axis copies' type: uint8 as it is, anything else float32. Why: the copies are read once
    per segment and are much of a frame's memory traffic on sparse scenes (aneurism's float32 copy
    is 64 MB, as uint8 16 MB): 10-18 % less compositing there, and 4x less memory
    (docs/shearwarp.md)."""
    return np.dtype(dtype) if np.dtype(dtype) in KEPT_COPY_DTYPES else np.dtype(np.float32)


@dataclass
class AxisCopy:
    """The volume's values laid out for one principal axis: `values[k, b, a]`, in `copy_dtype`."""

    axis: int
    values: NDArray[np.float32] | NDArray[np.uint8]
    runs: dict[tuple, Runs] = field(default_factory=dict)  #: by (extent, the `slab_pairs` as bytes)
    #: by (extent, the `slab_pairs` as bytes): each block's (lowest, highest) range bin, uint8
    #: (`_block_ranges`), kept across TF edits
    ranges: dict[tuple, tuple[NDArray[np.uint8], NDArray[np.uint8]]] = field(default_factory=dict)
    ranges_key: tuple[float, float] | None = None  #: the value range the bins span


@dataclass(frozen=True)
class Runs:
    """Runs of possibly visible blocks: for slab k (the k-th of `slab_pairs`: slices k, k + 1 at
    stride 1) and block row j, the runs `starts[i]:ends[i]` (block indices along a) for i in
    `offsets[k * (nb - 1 + extent) + j]` up to the next; block (j, i) is cells j - extent .. j by
    i - extent .. i (`_block_ranges`)."""

    offsets: NDArray[np.int64]
    starts: NDArray[np.int32]
    ends: NDArray[np.int32]
    digest: str
    extent: int
    build_ms: float
    visible_cells: int
    total_cells: int

    @property
    def nbytes(self) -> int:
        return int(self.offsets.nbytes + self.starts.nbytes + self.ends.nbytes)


#: Bins of the cached block ranges (`AxisCopy.ranges`): one byte each for a block's lowest and highest
#: value, 16 support bins per range bin (a range bin is visible when any of its support bins is:
#: conservative, so a TF edit can never hide a visible cell).
RANGE_BINS = 256


@njit(nogil=True, parallel=True, cache=True)
def _block_ranges(vol, pairs, lo, scale, bins, extent, bmin, bmax):
    """bmin, bmax[k, j, i] = the range bins (of RANGE_BINS over [lo, hi]) of the lowest and highest
    value over the vertices, in both slices of slab k (pairs[k]), of the anchored block of cells
    j - extent .. j by i - extent .. i (clipped to the slice: j and i run to n - 2 + extent);
    bmin > bmax where the block has no finite vertex (transparent).

    Why cached: this is the TF-independent part of classifying a cell, and most of its cost; an
    opacity edit then only compares each block's range with the new support (`_mask_from_ranges`).
    The range is taken separably (slices, then a, then b: a window of extent + 2 vertices per
    axis), 3x fewer operations than per cell and block. Non-finite vertices are left out, which can
    only widen the range of a block whose cells are transparent anyway (conservative)."""
    nc, nb, na = vol.shape
    shift = 0
    while (RANGE_BINS << shift) < bins:
        shift += 1
    for k in prange(pairs.shape[0]):
        k0 = pairs[k, 0]
        k1 = pairs[k, 1]
        vmin = np.empty((nb, na), np.float32)
        vmax = np.empty((nb, na), np.float32)
        for b in range(nb):
            for a in range(na):
                v0 = np.float32(vol[k0, b, a])
                v1 = np.float32(vol[k1, b, a])
                ok0 = math.isfinite(v0)
                ok1 = math.isfinite(v1)
                if ok0 and ok1:
                    vmin[b, a] = min(v0, v1)
                    vmax[b, a] = max(v0, v1)
                elif ok0 or ok1:
                    vmin[b, a] = v0 if ok0 else v1
                    vmax[b, a] = v0 if ok0 else v1
                else:
                    vmin[b, a] = np.inf
                    vmax[b, a] = -np.inf
        rmin = np.empty((nb, na - 1 + extent), np.float32)
        rmax = np.empty((nb, na - 1 + extent), np.float32)
        for b in range(nb):
            for i in range(na - 1 + extent):
                mn = np.float32(np.inf)
                mx = np.float32(-np.inf)
                for a2 in range(max(i - extent, 0), min(i + 1, na - 1) + 1):
                    mn = min(mn, vmin[b, a2])
                    mx = max(mx, vmax[b, a2])
                rmin[b, i] = mn
                rmax[b, i] = mx
        for j in range(nb - 1 + extent):
            for i in range(na - 1 + extent):
                mn = np.float32(np.inf)
                mx = np.float32(-np.inf)
                for b2 in range(max(j - extent, 0), min(j + 1, nb - 1) + 1):
                    mn = min(mn, rmin[b2, i])
                    mx = max(mx, rmax[b2, i])
                if mn > mx:
                    bmin[k, j, i] = RANGE_BINS - 1
                    bmax[k, j, i] = 0
                else:  # the support's own bins (as `OpacitySupport` bins values), then 2^shift of them per range bin
                    bmin[k, j, i] = min(max(int((mn - lo) * scale), 0), bins - 1) >> shift
                    bmax[k, j, i] = min(max(int((mx - lo) * scale), 0), bins - 1) >> shift


@njit(nogil=True, parallel=True, cache=True)
def _mask_from_ranges(bmin, bmax, counts, mask):
    """mask = 1 where a block's range bins hold a bin with nonzero opacity (`counts`: prefix counts
    over the range bins)."""
    nk, nb, na = bmin.shape
    for k in prange(nk):
        for b in range(nb):
            for a in range(na):
                lo_bin = bmin[k, b, a]
                hi_bin = bmax[k, b, a]
                mask[k, b, a] = 1 if lo_bin <= hi_bin and counts[hi_bin + 1] - counts[lo_bin] > 0 else 0


def range_counts(support: OpacitySupport) -> NDArray[np.int32]:
    """Prefix counts over RANGE_BINS bins of the support (a range bin counts when any of its bins does)."""
    bins = support.counts.shape[0] - 1
    per = max(1, bins // RANGE_BINS)
    edges = np.minimum(np.arange(RANGE_BINS + 1) * per, bins)
    nonzero = support.counts[edges[1:]] - support.counts[edges[:-1]] > 0
    counts = np.zeros(RANGE_BINS + 1, np.int32)
    np.cumsum(nonzero, out=counts[1:])
    return counts


@njit(nogil=True, cache=True, inline="always")
def _row_runs(mask, k, b, min_gap, starts, ends, at):
    """The runs of row (k, b) of `mask`, gaps shorter than `min_gap` cells bridged; written at
    `at` when starts has room, counted either way."""
    na = mask.shape[2]
    count = 0
    a = 0
    while a < na:
        if not mask[k, b, a]:
            a += 1
            continue
        e = a
        while e < na:
            while e < na and mask[k, b, e]:
                e += 1
            g = e
            while g < na and not mask[k, b, g]:
                g += 1
            if g < na and g - e < min_gap:
                e = g  # a short gap: walking it costs less than a run
            else:
                break
        if starts.shape[0] > 0:
            starts[at + count] = a
            ends[at + count] = e
        count += 1
        a = e
    return count


@njit(nogil=True, parallel=True, cache=True)
def _runs_from_mask(mask, min_gap):
    nk, nb, na = mask.shape
    per_row = np.zeros(nk * nb, np.int64)
    empty = np.empty(0, np.int32)
    for r in prange(nk * nb):
        per_row[r] = _row_runs(mask, r // nb, r % nb, min_gap, empty, empty, 0)
    offsets = np.zeros(nk * nb + 1, np.int64)
    offsets[1:] = np.cumsum(per_row)
    starts = np.empty(offsets[-1], np.int32)
    ends = np.empty(offsets[-1], np.int32)
    for r in prange(nk * nb):
        _row_runs(mask, r // nb, r % nb, min_gap, starts, ends, offsets[r])
    return offsets, starts, ends


def block_ranges(values: NDArray[np.float32], support: OpacitySupport, extent: int,
                 pairs: NDArray[np.int64]) -> tuple[NDArray, NDArray]:  # fmt: skip
    """`_block_ranges` of one axis copy for the slabs `pairs` (`slab_pairs`), bins over the
    support's value range, fixed per volume."""
    nc, nb, na = values.shape
    bmin = np.empty((pairs.shape[0], nb - 1 + extent, na - 1 + extent), np.uint8)
    bmax = np.empty((pairs.shape[0], nb - 1 + extent, na - 1 + extent), np.uint8)
    bins = support.counts.shape[0] - 1
    _block_ranges(values, pairs, support.lo, bins / (support.hi - support.lo), bins, extent, bmin, bmax)
    return bmin, bmax


def build_runs(ranges: tuple[NDArray, NDArray], support: OpacitySupport, extent: int) -> Runs:
    """The runs of one axis copy for this opacity support, for rays that move at most `extent`
    cells in the slice plane across a slab, from its cached block ranges."""
    start = time.perf_counter()
    bmin, bmax = ranges
    mask = np.empty(bmin.shape, np.uint8)
    _mask_from_ranges(bmin, bmax, range_counts(support), mask)
    offsets, starts, ends = _runs_from_mask(mask, MIN_GAP)
    visible = int(mask.sum(dtype=np.int64))
    ms = (time.perf_counter() - start) * 1000.0
    return Runs(offsets, starts, ends, support.digest, extent, ms, visible, int(mask.size))


@dataclass
class ClassifiedVolume:
    """The three axis copies of one volume (made on first use) and their runs for the current support."""

    volume: UniformVolume
    copies: dict[int, AxisCopy] = field(default_factory=dict)
    copy_ms: dict[int, float] = field(default_factory=dict)
    has_nan: bool = field(init=False)

    def __post_init__(self) -> None:
        # the compositing kernels test segments for NaN only when the volume has one (a test per segment)
        self.has_nan = (
            bool(np.isnan(self.volume.values).any()) if self.volume.values.dtype.kind == "f" else False
        )

    def copy(self, axis: int) -> AxisCopy:
        found = self.copies.get(axis)
        if found is None:
            start = time.perf_counter()
            a, b, c = PERMS[axis]
            # values are indexed [z, y, x]: volume axis i is array axis 2 - i
            values = np.ascontiguousarray(np.transpose(self.volume.values, (2 - c, 2 - b, 2 - a)),
                                          dtype=copy_dtype(self.volume.values.dtype))  # fmt: skip
            found = AxisCopy(axis, values)
            self.copies[axis] = found
            self.copy_ms[axis] = (time.perf_counter() - start) * 1000.0
        return found

    def runs(
        self, axis: int, support: OpacitySupport, extent: int = 1, pairs: NDArray[np.int64] | None = None
    ) -> Runs:
        """The runs of `axis` for `support` and `extent` over the slabs `pairs` (`slab_pairs` of the
        compositing order; default every slice), rebuilt only when the support changed."""
        copy = self.copy(axis)
        if pairs is None:
            pairs = slab_pairs(np.arange(copy.values.shape[0]))[0]
        key = (extent, pairs.tobytes())
        found = copy.runs.get(key)
        if found is None or found.digest != support.digest:
            if copy.ranges_key != (support.lo, support.hi):
                copy.ranges.clear()
                copy.ranges_key = (support.lo, support.hi)
            if key not in copy.ranges:
                copy.ranges[key] = block_ranges(copy.values, support, extent, pairs)
            found = copy.runs[key] = build_runs(copy.ranges[key], support, extent)
        return found

    @property
    def nbytes(self) -> int:
        """Bytes held by the copies, their runs and their cached block ranges."""
        return sum(c.values.nbytes + sum(r.nbytes for r in c.runs.values())
                   + sum(lo.nbytes + hi.nbytes for lo, hi in c.ranges.values()) for c in self.copies.values())  # fmt: skip
