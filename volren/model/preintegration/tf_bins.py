"""Exact per-bin means of the extinction and the emission of a 1D transfer function.

Why: pre-integration composites the value axis bin by bin. Sampling the TF at the bin edges would
alias every feature narrower than a bin (a thin spike between two samples vanishes, one on a
sample is smeared over two bins). Each bin instead carries the exact mean over its span of values
of the extinction tau(s) and of the emission q(s) = c(s) tau(s), so the optical depth of every
segment is exact whatever the table size, and narrow spikes keep their weight and their colour.

How: the value axis is cut at the bin edges and at `TransferFunction1D.linear_cuts` (control
points and clamp crossings); on each piece ("atom") the colour and the clamped opacity are linear.
On an atom, with t in [0, 1], w = 1 - a = wm (1 + e v), v = 2t - 1, e = (w1 - w0) / (w1 + w0),
colour c = cm + (dc / 2) v:

    d_u mean(tau)   = M0 = -ln(wm) - I0(e),   I0 = ((1+e) ln(1+e) - (1-e) ln(1-e)) / (2e) - 1
    d_u mean(c tau) = cm M0 - (dc / 2) I1(e), I1 = (2e - (1 - e^2) ln((1+e)/(1-e))) / (4 e^2)

with Taylor series in e where the closed forms cancel (|e| < 0.1). The end values of a and c on
an atom are extrapolated from its quarter points, so steps in the TF (duplicated control points)
give each side its own one-sided limit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from volren.model.transfer_function import MAX_OPACITY, TransferFunction1D

#: Below this |e| the series are used (their first omitted term is below 1e-17 relative).
_SERIES_LIMIT = 0.1


@dataclass(frozen=True)
class TFBins:
    """The TF averaged over `count` equal bins of [lo, hi], per unit length (world units).

    tau (count,): mean extinction; color (count, 3): emission-weighted mean colour q / tau, which
    is what a homogeneous stand-in for the bin must emit (0 where the bin is transparent).
    """

    lo: float
    hi: float
    tau: NDArray[np.float64]
    color: NDArray[np.float64]

    @property
    def count(self) -> int:
        return int(self.tau.shape[0])


def _i0(e: NDArray[np.float64]) -> NDArray[np.float64]:
    """(1/2) * integral over v in [-1, 1] of ln(1 + e v)."""
    small = np.abs(e) < _SERIES_LIMIT
    e2 = np.where(small, e * e, 0.0)
    series = -e2 * (
        1 / 6 + e2 * (1 / 20 + e2 * (1 / 42 + e2 * (1 / 72 + e2 * (1 / 110 + e2 * (1 / 156 + e2 / 210)))))
    )
    el = np.where(small, 0.5, e)  # any value where the closed form is not used
    closed = ((1 + el) * np.log1p(el) - (1 - el) * np.log1p(-el)) / (2 * el) - 1
    return np.where(small, series, closed)


def _i1(e: NDArray[np.float64]) -> NDArray[np.float64]:
    """(1/2) * integral over v in [-1, 1] of v ln(1 + e v)."""
    small = np.abs(e) < _SERIES_LIMIT
    es = np.where(small, e, 0.0)
    e2 = es * es
    series = es * (
        1 / 3 + e2 * (1 / 15 + e2 * (1 / 35 + e2 * (1 / 63 + e2 * (1 / 99 + e2 * (1 / 143 + e2 / 195)))))
    )
    el = np.where(small, 0.5, e)
    closed = (2 * el - (1 - el * el) * (np.log1p(el) - np.log1p(-el))) / (4 * el * el)
    return np.where(small, series, closed)


def atom_means(
    a0: NDArray, a1: NDArray, c0: NDArray, c1: NDArray
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Exact means of -ln(1 - a) and of c * -ln(1 - a) where a runs linearly from a0 to a1 (both
    at most the clamp) and c (..., 3) linearly from c0 to c1: ((n,), (n, 3)), in units of 1 / d_u."""
    w0 = 1.0 - a0
    w1 = 1.0 - a1
    wm = 0.5 * (w0 + w1)
    e = (w1 - w0) / (w1 + w0)
    m0 = -np.log(wm) - _i0(e)
    cm = 0.5 * (c0 + c1)
    m1 = cm * m0[:, None] - 0.5 * (c1 - c0) * _i1(e)[:, None]
    return m0, m1


def _tf_linear_ends(
    tf: TransferFunction1D, x0: NDArray, x1: NDArray
) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """Opacity and colour at both ends of atoms on which the TF is linear (one-sided limits)."""
    width = x1 - x0
    rgb_q1, a_q1 = tf.sample(x0 + 0.25 * width)
    rgb_q3, a_q3 = tf.sample(x0 + 0.75 * width)
    a0 = np.clip(1.5 * a_q1 - 0.5 * a_q3, 0.0, MAX_OPACITY)
    a1 = np.clip(1.5 * a_q3 - 0.5 * a_q1, 0.0, MAX_OPACITY)
    c0 = np.clip(1.5 * rgb_q1 - 0.5 * rgb_q3, 0.0, 1.0)
    c1 = np.clip(1.5 * rgb_q3 - 0.5 * rgb_q1, 0.0, 1.0)
    return a0, a1, c0, c1


def point_values(tf: TransferFunction1D, values: NDArray) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """tau (n,) and colour (n, 3) at single values (the homogeneous segments on the diagonal)."""
    rgb, _ = tf.sample(values)
    return tf.extinction(values), rgb


def bin_edges(lo: float, hi: float, count: int) -> NDArray[np.float64]:
    edges = lo + (hi - lo) * (np.arange(count + 1, dtype=np.float64) / count)
    edges[-1] = hi
    return edges


def tf_bins(tf: TransferFunction1D, lo: float, hi: float, count: int) -> TFBins:
    """Exact means of tau and q over `count` equal bins of [lo, hi] (lo <= hi, both finite)."""
    edges = bin_edges(lo, hi, count)
    cuts = tf.linear_cuts()
    cuts = cuts[(cuts > lo) & (cuts < hi)]
    xs = np.unique(np.concatenate([edges, cuts]))
    x0, x1 = xs[:-1], xs[1:]
    bin_width = edges[1:] - edges[:-1]
    tau = np.zeros(count)
    q = np.zeros((count, 3))
    if len(x0):
        a0, a1, c0, c1 = _tf_linear_ends(tf, x0, x1)
        m0, m1 = atom_means(a0, a1, c0, c1)
        # by the left end: bins narrower than the float spacing share an edge value, and the
        # last of them is the one that actually spans the atom
        owner = np.clip(np.searchsorted(edges, x0, side="right") - 1, 0, count - 1)
        share = (x1 - x0) / bin_width[owner]  # fractions of a bin: no overflow for huge ranges
        tau = np.bincount(owner, weights=share * m0, minlength=count)  # type: ignore[assignment]  # float with weights; numpy's stubs say int
        q = np.stack(
            [np.bincount(owner, weights=share * m1[:, c], minlength=count) for c in range(3)], axis=1
        )
    unit = tf.opacity_unit_distance
    tau /= unit
    q /= unit
    empty = ~(bin_width > 0)
    if empty.any():  # bins narrower than the float spacing of [lo, hi]: the TF at that value
        tau[empty], rgb = point_values(tf, edges[:-1][empty])
        q[empty] = rgb * tau[empty, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        color = np.where(tau[:, None] > 0, q / np.where(tau > 0, tau, 1.0)[:, None], 0.0)
    # q <= c_max tau holds exactly; the two closed forms may differ by rounding.
    return TFBins(lo, hi, tau, np.clip(color, 0.0, 1.0))
