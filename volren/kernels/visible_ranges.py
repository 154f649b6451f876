"""Which value ranges a 1D transfer function makes visible: opacity above zero somewhere in
[lo, hi], for every cell or brick at once.

Why not `model.bricks.max_opacity_between` (the largest opacity, which it also gives): skipping
only asks whether that maximum is positive, which needs no interpolation. A piecewise-linear
opacity is positive somewhere in [lo, hi] exactly when a control point inside has a positive
opacity, or a part of a gap between control points that [lo, hi] covers has a positive end (the
TF is linear in a gap, so positive on all of it but a zero end; beyond the ends it is constant). Two binary searches per
range in one parallel numba pass: 31 ms -> a few ms for oxygen's 513k cells on each TF edit.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange
from numpy.typing import ArrayLike, NDArray

from volren.model.transfer_function import TransferFunction1D


@njit(nogil=True, parallel=True, cache=True)
def _visible(xs, positive_before, gap_positive, lo, hi, out):
    for q in prange(lo.shape[0]):
        a, b = lo[q], hi[q]
        if not (np.isfinite(a) and np.isfinite(b)):
            out[q] = False
            continue
        first = np.searchsorted(xs, a, side="left")  # first control point >= a
        stop = np.searchsorted(xs, b, side="right")  # first control point > b
        if stop == first:  # no control point inside: [a, b] lies in one gap, where the TF is linear
            out[q] = gap_positive[first]
        else:  # the points inside, and the parts of the gaps before the first and after the last
            out[q] = (positive_before[stop] > positive_before[first]
                      or (a < xs[first] and gap_positive[first])
                      or (b > xs[stop - 1] and gap_positive[stop]))  # fmt: skip


def visible_ranges(tf: TransferFunction1D, lo: ArrayLike, hi: ArrayLike) -> NDArray[np.bool_]:
    """For each range [lo, hi] (lo <= hi): whether the TF's opacity is above zero somewhere in it;
    False where lo or hi is not finite."""
    lo = np.ascontiguousarray(lo, dtype=np.float64)
    hi = np.ascontiguousarray(hi, dtype=np.float64)
    points = tf.opacity_points
    xs = np.ascontiguousarray(points[:, 0], dtype=np.float64)
    positive = np.clip(points[:, 1], 0.0, 1.0) > 0.0
    positive_before = np.concatenate([[0], np.cumsum(positive)]).astype(np.int64)  # count among xs[:k]
    # gap k lies between xs[k - 1] and xs[k]; gaps 0 and m lie beyond the ends (constant there)
    gap_positive = np.concatenate([positive[:1], positive[:-1] | positive[1:], positive[-1:]])
    out = np.empty(lo.size, dtype=np.bool_)
    _visible(xs, positive_before, gap_positive, lo.reshape(-1), hi.reshape(-1), out)
    return out.reshape(lo.shape)
