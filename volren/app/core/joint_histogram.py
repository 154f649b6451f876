"""The joint histogram of data value and gradient magnitude: the 2D TF editor's background.

Why: in a (value, |grad s|) scatter plot homogeneous materials show up as blobs at the bottom and
the boundaries between them as arches joining pairs of blobs (Real-Time Volume Graphics, section 10.3-10.4), so the
editor draws it behind the widgets, on exactly the TF's axes (value range x [0, gmax]).

Gradients are the renderers' own (reference `shading`, the slicer's gradient texture):

- uniform grids: central differences at the grid points in world units, one-sided at the borders
  (np.gradient with the spacing). One sample per grid point, each counting 1. Volumes of more
  than `MAX_SAMPLES` points are subsampled deterministically: every `stride`-th point along each
  axis, the smallest stride that fits, with the gradient still taken from the point's full-
  resolution neighbours (bonsai, 256^3 = 2^24 points, is done in full: about 0.2 s).
- tetrahedral meshes: one sample per tetrahedron, the constant gradient of its linear field
  (`tet_mesh.prepare_mesh`, what the mesh renderers shade with) and the value at its centroid
  (the mean of the four vertex values, which is also the tet's mean value). Per-point values with
  averaged gradients were the alternative; they would show gradients no renderer uses. Each tet
  counts its volume in units of the mean tet volume, so the density means what it means on a
  grid (how much of space has that pair) and totals the number of tets. Flat tets (no volume)
  and tets with a non-finite vertex value are left out.

Samples with a non-finite value or gradient are left out; those beyond the gradient axis are not
drawn (they are counted in `JointHistogram.above`) rather than piled into the top row. Bins are
uniform: value bin i covers [lo + i w, lo + (i + 1) w), gradient bin j likewise from 0, and the
top edges are closed. `log_density` is log(1 + count) scaled to [0, 1].

The default gradient axis (`GradientStats.robust_max`) is the 99.5th percentile of the non-zero
gradient magnitudes (Real-Time Volume Graphics' "largest significant gradient magnitude"; zeros are left out so
that mostly empty volumes such as bonsai do not push it down), estimated from at most
`STATS_SAMPLES` strided samples. Results are cached per volume object (weakly: a volume that is
dropped takes its entries with it).
"""

from __future__ import annotations

import math
import weakref
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numba import njit
from numpy.typing import NDArray

from volren.errors import VolrenError
from volren.model.tet_mesh import prepare_mesh
from volren.model.volume import TetVolume, UniformVolume, Volume

#: Grid points above which a uniform volume's histogram is taken on a strided subset.
MAX_SAMPLES = 1 << 24
#: Grid points the gradient statistics are estimated from (at most).
STATS_SAMPLES = 1 << 20
#: The percentile of the non-zero gradient magnitudes that sets the default gradient axis.
ROBUST_PERCENTILE = 99.5
#: Default bins: (values, gradient magnitudes).
DEFAULT_BINS = (256, 128)
#: Histograms kept per volume (the gradient axis changes while someone edits it).
_HISTOGRAMS_PER_VOLUME = 8


@dataclass(frozen=True)
class GradientStats:
    """Gradient magnitudes of a volume: the largest seen and a robust maximum for the TF axis."""

    max: float
    robust_max: float
    samples: int


@dataclass(frozen=True, eq=False)
class JointHistogram:
    """Counts over value x gradient magnitude; `counts[j, i]`: gradient bin j (0 at g = 0), value bin i.

    The orientation is `TransferFunction2D.table`'s: rows are gradient magnitudes, columns values.
    """

    counts: NDArray[np.float64]
    value_range: tuple[float, float]
    gradient_max: float
    #: 1: every grid point (or tet); s: every s-th point along each axis.
    stride: int
    #: Weight of the samples with a gradient magnitude above `gradient_max` (not in `counts`).
    above: float
    log_density: NDArray[np.float64] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        top = float(self.counts.max(initial=0.0))
        density = np.log1p(self.counts) / math.log1p(top) if top > 0 else np.zeros_like(self.counts)
        object.__setattr__(self, "log_density", density)

    @property
    def shape(self) -> tuple[int, int]:
        """(n_gradients, n_values)."""
        return self.counts.shape  # type: ignore[return-value]


# ---------------------------------------------------------------------------------- caching
_cache: weakref.WeakKeyDictionary[Volume, dict[str, Any]] = weakref.WeakKeyDictionary()


def _entry(volume: Volume) -> dict[str, Any]:
    entry = _cache.get(volume)
    if entry is None:
        entry = {"histograms": OrderedDict()}
        _cache[volume] = entry
    return entry


def clear_cache() -> None:
    """Forget every cached statistic and histogram (tests time the uncached path with it)."""
    _cache.clear()


# ---------------------------------------------------------------------------- uniform grids
@njit(nogil=True, cache=True)
def _axis_steps(n, stride):
    return (n + stride - 1) // stride


@njit(nogil=True, cache=True)
def _row(V, k, j, stride, ihx, ihy, ihz, vals, mags):
    """Values and |grad s| at the grid points (k, j, 0), (k, j, stride), ... into vals, mags;
    returns their number. Central differences, one-sided at the borders (np.gradient's rule)."""
    nz, ny, nx = V.shape
    j0 = max(j - 1, 0)
    j1 = min(j + 1, ny - 1)
    k0 = max(k - 1, 0)
    k1 = min(k + 1, nz - 1)
    fy = ihy / (j1 - j0)
    fz = ihz / (k1 - k0)
    n = 0
    for i in range(0, nx, stride):
        i0 = max(i - 1, 0)
        i1 = min(i + 1, nx - 1)
        gx = (float(V[k, j, i1]) - float(V[k, j, i0])) * (ihx / (i1 - i0))
        gy = (float(V[k, j1, i]) - float(V[k, j0, i])) * fy
        gz = (float(V[k1, j, i]) - float(V[k0, j, i])) * fz
        vals[n] = float(V[k, j, i])
        mags[n] = math.sqrt(gx * gx + gy * gy + gz * gz)
        n += 1
    return n


@njit(nogil=True, cache=True)
def _grid_magnitudes(V, ihx, ihy, ihz, stride):
    """|grad s| at every stride-th grid point along each axis (NaN where the value is not finite)."""
    nz, ny, nx = V.shape
    out = np.empty(_axis_steps(nz, stride) * _axis_steps(ny, stride) * _axis_steps(nx, stride))
    vals = np.empty(nx)
    mags = np.empty(nx)
    n = 0
    for k in range(0, nz, stride):
        for j in range(0, ny, stride):
            m = _row(V, k, j, stride, ihx, ihy, ihz, vals, mags)
            for i in range(m):
                out[n] = mags[i] if math.isfinite(vals[i]) else math.nan
                n += 1
    return out


@njit(nogil=True, cache=True)
def _grid_histogram(V, ihx, ihy, ihz, stride, lo, hi, gmax, counts):
    """Add every stride-th grid point to counts (n_gradients, n_values); returns the weight above gmax."""
    nz, ny, nx = V.shape
    ng, nv = counts.shape
    sv = nv / (hi - lo)
    sg = ng / gmax
    above = 0.0
    vals = np.empty(nx)
    mags = np.empty(nx)
    for k in range(0, nz, stride):
        for j in range(0, ny, stride):
            m = _row(V, k, j, stride, ihx, ihy, ihz, vals, mags)
            for i in range(m):
                v = vals[i]
                g = mags[i]
                if not (math.isfinite(v) and math.isfinite(g)):
                    continue
                if g > gmax:
                    above += 1.0
                    continue
                if v < lo or v > hi:
                    continue
                a = min(int((v - lo) * sv), nv - 1)
                b = min(int(g * sg), ng - 1)
                counts[b, a] += 1.0
    return above


def _stride_for(volume: UniformVolume, limit: int) -> int:
    """The smallest stride whose lattice has at most `limit` points."""
    nx, ny, nz = volume.dimensions
    stride = 1
    while math.ceil(nx / stride) * math.ceil(ny / stride) * math.ceil(nz / stride) > limit:
        stride += 1
    return stride


def _inverse_spacing(volume: UniformVolume) -> tuple[float, float, float]:
    hx, hy, hz = volume.spacing
    return 1.0 / hx, 1.0 / hy, 1.0 / hz


# ------------------------------------------------------------------------ tetrahedral meshes
def _tet_samples(volume: TetVolume) -> tuple[NDArray, NDArray, NDArray]:
    """(centroid values, gradient magnitudes, weights) of the usable tets (see the module docstring)."""
    entry = _entry(volume)
    if "tet_samples" not in entry:
        mesh = prepare_mesh(volume)
        p = mesh.points[mesh.tets]
        det = np.einsum("ij,ij->i", p[:, 1] - p[:, 0], np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]))
        vol = np.abs(det) / 6.0
        values = mesh.values[mesh.tets].mean(axis=1)
        grads = np.linalg.norm(mesh.gradients, axis=1)
        usable = ~mesh.flat & ~mesh.nonfinite & np.isfinite(values) & np.isfinite(grads) & (vol > 0)
        vol = vol[usable]
        weights = vol / vol.mean() if vol.size else vol
        entry["tet_samples"] = (values[usable], grads[usable], weights)
    return entry["tet_samples"]


# ------------------------------------------------------------------------------ public API
def gradient_stats(volume: Volume) -> GradientStats:
    """Largest and robust (99.5th percentile of the non-zero) gradient magnitudes, cached."""
    entry = _entry(volume)
    if "stats" not in entry:
        if isinstance(volume, UniformVolume):
            stride = _stride_for(volume, STATS_SAMPLES)
            mags = _grid_magnitudes(volume.values, *_inverse_spacing(volume), stride)
            mags = mags[np.isfinite(mags)]
            weights = None
        else:
            _, mags, weights = _tet_samples(volume)
        entry["stats"] = _stats(mags, weights)
    return entry["stats"]


def _stats(mags: NDArray, weights: NDArray | None) -> GradientStats:
    positive = mags > 0
    if not positive.any():
        return GradientStats(0.0, 0.0, int(mags.size))
    top = float(mags.max())
    if weights is None:
        robust = float(np.percentile(mags[positive], ROBUST_PERCENTILE))
    else:
        order = np.argsort(mags[positive])
        sorted_mags = mags[positive][order]
        cumulative = np.cumsum(weights[positive][order])
        k = int(np.searchsorted(cumulative, cumulative[-1] * ROBUST_PERCENTILE / 100.0))
        robust = float(sorted_mags[min(k, sorted_mags.size - 1)])
    return GradientStats(top, robust, int(mags.size))


def suggested_gradient_max(volume: Volume) -> float:
    """The gradient axis a new 2D TF gets: the robust maximum, else the maximum, else 1."""
    stats = gradient_stats(volume)
    for candidate in (stats.robust_max, stats.max):
        if candidate > 0 and math.isfinite(candidate):
            return candidate
    return 1.0


def joint_histogram(
    volume: Volume,
    n_values: int = DEFAULT_BINS[0],
    n_gradients: int = DEFAULT_BINS[1],
    gradient_max: float | None = None,
    value_range: tuple[float, float] | None = None,
) -> JointHistogram:
    """The histogram on value_range (default: the volume's) x [0, gradient_max] (default: the
    robust maximum); cached per volume and arguments."""
    if n_values < 1 or n_gradients < 1:
        raise VolrenError(
            f"a joint histogram needs at least one bin per axis, got {n_values} x {n_gradients}"
        )
    lo, hi = value_range if value_range is not None else volume.value_range
    lo, hi = float(lo), float(hi)
    if not hi > lo:
        lo, hi = lo - 0.5, hi + 0.5  # a constant volume: one value, shown in the middle
    gmax = float(gradient_max) if gradient_max is not None else suggested_gradient_max(volume)
    if not (gmax > 0 and math.isfinite(gmax)):
        raise VolrenError(f"the gradient axis of a joint histogram must end above 0, got {gmax:g}")
    key = (int(n_values), int(n_gradients), gmax, lo, hi)
    histograms: OrderedDict = _entry(volume)["histograms"]
    if key in histograms:
        histograms.move_to_end(key)
        return histograms[key]
    counts = np.zeros((int(n_gradients), int(n_values)))
    if isinstance(volume, UniformVolume):
        stride = _stride_for(volume, MAX_SAMPLES)
        above = _grid_histogram(volume.values, *_inverse_spacing(volume), stride, lo, hi, gmax, counts)
    else:
        stride = 1
        values, mags, weights = _tet_samples(volume)
        above = float(weights[mags > gmax].sum())
        keep = (mags <= gmax) & (values >= lo) & (values <= hi)
        a = np.minimum(((values[keep] - lo) * (n_values / (hi - lo))).astype(np.int64), n_values - 1)
        b = np.minimum((mags[keep] * (n_gradients / gmax)).astype(np.int64), n_gradients - 1)
        np.add.at(counts, (b, a), weights[keep])
    result = JointHistogram(counts, (lo, hi), gmax, stride, float(above))
    histograms[key] = result
    while len(histograms) > _HISTOGRAMS_PER_VOLUME:
        histograms.popitem(last=False)
    return result
