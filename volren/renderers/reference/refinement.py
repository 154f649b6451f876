"""The refinement around the reference's quadrature: one ray's cut points and its levels, for 1D and
2D transfer functions alike.

Why: a 2D TF (`tf2d`) needs other cut points and another quadrature per level than a 1D TF
(`ray_integral`), but the same scaffolding around them; one copy of it keeps the two integrals
refined and stopped by the same rule.

Per ray, `integrate_ray` gets the ray's intervals (`uniform.build_intervals`, `tets`) and
1. sorts the cut points of every interval into one CSR table (`compute_cuts`) and cuts each
   interval into the level-0 pieces both quadratures start from (`level0_pieces`);
2. computes levels (level L bisects every level-0 sub-piece L times) until the change between two
   successive ones is below `tol` and the change before it below ASYMPTOTIC_RATIO * tol (level 1,
   having none before it, must change by less than tol / ASYMPTOTIC_RATIO), so two coarse levels
   agreeing by accident do not stop a ray; at most `max_levels` levels, the finest one computed is
   the result. The change is the max abs over the four channels of the pixel (1D) or, with a 2D
   TF, of the sum over the intervals of the change of each interval's share of the pixel, so that
   changes in different cells cannot cancel.

Exactly one of `tf` (a packed 1D TF, `volren.kernels.tf_eval.pack_tf`) and `tf2d`
(`tf2d.pack_tf2d`) is given, the other is None: numba compiles only the branches of the one given.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from volren.kernels.shading import half_vector
from volren.renderers.reference.ray_integral import (
    COMPOSITE,
    _composite_level,
    interval_cuts_1d,
    next_boundary,
    project_ray,
)
from volren.renderers.reference.tf2d import _composite_level_2d, interval_cuts_2d, share_change

#: A level counts as converged when its change is below tol and the previous change was below
#: this times tol (an h^2 sequence shrinks its changes by 4 per level).
ASYMPTOTIC_RATIO = 4.0


@njit(nogil=True, cache=True)
def _cuts_of(P, G, k, length, tf, tf2d, shading, thr2, out):
    """The cut points of interval k, sorted into out when it holds them all; returns their count."""
    n = 0
    if tf is not None:
        n = interval_cuts_1d(P[k], G, k, length, tf.cuts, shading, thr2, out)
    if tf2d is not None:
        n = interval_cuts_2d(P[k], G[k], length, tf2d, shading, thr2, out)
    return n


@njit(nogil=True, cache=True)
def compute_cuts(ta, tb, P, G, m, tf, tf2d, shading, thr):
    """CSR of the sorted cut points of every interval: (offsets (m + 1), cuts)."""
    offsets = np.zeros(m + 1, np.int64)
    empty = np.empty(0)
    thr2 = thr * thr
    for k in range(m):
        length = tb[k] - ta[k]
        count = 0
        if length > 0.0:
            count = _cuts_of(P, G, k, length, tf, tf2d, shading, thr2, empty)
        offsets[k + 1] = offsets[k] + count
    cuts = np.empty(offsets[m])
    for k in range(m):
        length = tb[k] - ta[k]
        if length > 0.0:
            _cuts_of(P, G, k, length, tf, tf2d, shading, thr2, cuts[offsets[k] : offsets[k + 1]])
    return offsets, cuts


@njit(nogil=True, cache=True)
def level0_pieces(ta, tb, m, offsets, cuts, h0):
    """CSR of the level-0 pieces' ends of every interval, (starts (m + 1), ends): interval k is
    split into max(1, ceil(len / h0)) equal pieces intersected with its cuts (CSR `offsets`,
    `cuts`); the pieces of interval k end at ends[starts[k]:starts[k + 1]], the last at its
    length. Every level of both quadratures (1D and 2D TFs) bisects these."""
    bound = 0  # each end is a piece's end or a cut
    for k in range(m):
        length = tb[k] - ta[k]
        if length > 0.0:
            bound += max(1, int(math.ceil(length / h0))) + offsets[k + 1] - offsets[k]
    starts = np.zeros(m + 1, np.int64)
    ends = np.empty(bound)
    e = 0
    for k in range(m):
        starts[k] = e
        length = tb[k] - ta[k]
        if not (length > 0.0):
            continue
        n = max(1, int(math.ceil(length / h0)))
        piece = length / n
        ci = offsets[k]
        cend = offsets[k + 1]
        p = 1
        u0 = 0.0
        while u0 < length:
            u1, ci, p = next_boundary(u0, length, cuts, ci, cend, p, piece, n)
            if u1 <= u0:
                continue
            ends[e] = u1
            e += 1
            u0 = u1
    starts[m] = e
    return starts, ends


@njit(nogil=True, cache=True)
def converged(level, change, last, tol):
    """Whether level `level` (>= 1), `change` away from the level before, ends the refinement."""
    if level == 1:
        return change < tol / ASYMPTOTIC_RATIO
    return change < tol and last < ASYMPTOTIC_RATIO * tol


@njit(nogil=True, cache=True)
def integrate_ray(intervals, quad, tf, tf2d, sp, dx, dy, dz):
    """RGBA of one ray (direction d) over its `RayIntervals` intervals, integrated as the
    `Quadrature` quad says with the `ShadeParams` sp, and its statistics: (r, g, b, a, samples,
    level, converged, cap_hits)."""
    ta, tb, P, G, m = intervals
    mode, h0, tol, max_levels = quad
    if m == 0:
        return 0.0, 0.0, 0.0, 0.0, 0, 0, True, 0
    if tf is not None and mode != COMPOSITE:
        return project_ray(ta, tb, P, m, mode, tf)
    hx, hy, hz = half_vector(sp, dx, dy, dz)
    offsets, cuts = compute_cuts(ta, tb, P, G, m, tf, tf2d, sp.on, sp.gradient_threshold)
    pieces = level0_pieces(ta, tb, m, offsets, cuts, h0)
    shares = np.zeros((0, 4))
    before = np.zeros((0, 4))
    if tf2d is not None:  # a 2D TF's change is measured per interval
        shares = np.zeros((m, 4))
        before = np.zeros((m, 4))
    cr = cg = cb = ca = 0.0
    pr = pg = pb = pa = 0.0
    n = c = samples = caps = 0
    change = 0.0
    last = math.inf
    for level in range(max_levels):
        if tf is not None:
            cr, cg, cb, ca, n, c = _composite_level(intervals, pieces, level, tf, sp, hx, hy, hz)
            change = max(abs(cr - pr), abs(cg - pg), abs(cb - pb), abs(ca - pa))
        if tf2d is not None:
            cr, cg, cb, ca, n, c = _composite_level_2d(intervals, pieces, level, tf2d, sp, hx, hy, hz, shares)
            change = share_change(shares, before, m)
            before, shares = shares, before
        pr, pg, pb, pa = cr, cg, cb, ca
        samples += n
        caps += c
        if level > 0:
            if converged(level, change, last, tol):
                return pr, pg, pb, pa, samples, level, True, caps
            last = change
    return pr, pg, pb, pa, samples, max_levels - 1, False, caps
