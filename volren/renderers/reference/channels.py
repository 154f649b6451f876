"""Reference ray integration of multi-channel volumes on uniform grids (the model of
`volren.model.channels`: tau = sum_c w_c tau_c(s_c), q = sum_c w_c c_c(s_c) tau_c(s_c)).

Why: with several channels each point mixes several TFs of several scalars, so the plain
reference's per-piece exactness (one TF of one scalar, linear on each piece) no longer holds; this
is the reference's own quadrature of that model, in float64 and refined until it converges, that
channel paths of other renderers are measured against (Max 1995, section 2: absorbing and emitting
media add; Real-Time Volume Graphics, section 4.4: the emission-absorption integral).

How, per pixel ray:
1. Clip and walk the grid as the plain path does (`volren.kernels.box_clipping.clip_box`,
   `volren.kernels.clip_planes.clip_entry`, `uniform.build_intervals` over a grid of zeros: one
   interval per cell crossed, none dropped there).
2. Per interval, each drawn channel (weight > 0 and visible) whose eight corners are finite gets
   its trilinear value as a cubic in the ray parameter (`uniform.trilinear_cubic`). Non-finite
   values: a channel with a non-finite corner in a cell is transparent in that cell, and the
   other channels still count there (the plain path's rule, "a cell with a non-finite corner is
   transparent", applied per channel); a cell where no drawn channel is finite is dropped.
3. Cuts: where any channel's cubic crosses a breakpoint of its own TF or has a critical point
   (`ray_integral`'s exact roots on the cubic's monotone spans), so that on every piece each
   channel's TF is linear in its scalar and the integrand is smooth. The level-0 pieces are those
   of the plain path (`refinement.level0_pieces`: steps of h0 intersected with the cuts).
4. The channels are the terms of `mixture.integrate_mixture_ray` (each on its own scalar's cubic,
   scaled by its weight): tau = sum_c w_c tau_c(s_c(u)), q = sum_c w_c tau_c(s_c(u)) c_c(s_c(u)),
   refined level by level until it converges, as `labelled` is.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from volren.renderers.reference.mixture import integrate_mixture_ray
from volren.renderers.reference.ray_integral import store_pixel
from volren.renderers.reference.uniform import build_intervals, cell_frame, corners, ray_span, trilinear_cubic


@njit(nogil=True, cache=True)
def channel_intervals(o, d, grid, values, drawn, ta, tb, m, S, W, C, nc):
    """The drawn channels of the m intervals of one ray (`build_intervals`' cells) as `mixture`
    terms: drawn channel C[k, n] (an index into `drawn`, whose entries index values[c, k, j, i])
    on the scalar S[k, n] with weight W[k, n] = 1 (its own weight scales it), n < nc[k]. A channel
    with a non-finite corner is left out of its cell, a cell with no channel left is dropped, the
    others are moved to the front; returns their number."""
    org, sp = grid.origin, grid.spacing
    nz, ny, nx = values.shape[1], values.shape[2], values.shape[3]
    dims = (nx, ny, nz)
    cell = np.zeros(3, np.int64)
    loc = np.zeros(3)
    rate = np.zeros(3)
    kept = 0
    for k in range(m):
        cell_frame(o, d, org, sp, dims, ta[k], tb[k], cell, loc, rate)
        n = 0
        for e in range(drawn.shape[0]):
            v = corners(values[drawn[e]], cell[2], cell[1], cell[0])
            finite = True
            for q in range(8):
                if not math.isfinite(v[q]):
                    finite = False
            if not finite:
                continue
            C[kept, n] = e
            trilinear_cubic(v, (loc[0], loc[1], loc[2]), (rate[0], rate[1], rate[2]), S[kept, n])
            W[kept, n, 0] = 1.0
            W[kept, n, 1] = 0.0
            W[kept, n, 2] = 0.0
            W[kept, n, 3] = 0.0
            n += 1
        if n == 0:
            continue
        nc[kept] = n
        ta[kept] = ta[k]
        tb[kept] = tb[k]
        kept += 1
    return kept


@njit(nogil=True, parallel=True, cache=True)
def render_channels(orig, dirs, tfar, grid, values, drawn, tfs, weights, quad, out, stats):
    """One block of rays (origins, directions, far-plane parameters) through the `GridBox` grid
    (its values only give the walk its cells) with the channels values[c, k, j, i], of which those
    in `drawn` are drawn with the `PackedClasses` tfs and the weights (both indexed like `drawn`),
    composited as the `Quadrature` quad says: out (n, 4) float64 RGBA; stats (n, 5) = samples,
    level, unconverged, subdivision cap hits (none here), intervals (cells crossed)."""
    n = orig.shape[0]
    nz, ny, nx = grid.values.shape
    cap = nx + ny + nz + 4
    width = drawn.shape[0]
    for p in prange(n):
        o, d, t0, t1, _ = ray_span(orig, dirs, tfar, p, grid, out, stats)
        if not (t1 > t0):
            continue
        ta = np.empty(cap)
        tb = np.empty(cap)
        P = np.empty((cap, 4))
        G = np.empty((0, 3, 4))
        m = build_intervals(o, d, t0, t1, grid, False, ta, tb, P, G)
        C = np.empty((m, width), np.int64)
        S = np.empty((m, width, 4))
        W = np.empty((m, width, 4))
        nc = np.zeros(m, np.int64)
        kept = channel_intervals(o, d, grid, values, drawn, ta, tb, m, S, W, C, nc)
        result = integrate_mixture_ray(ta, tb, S, W, C, nc, kept, tfs, weights, quad)
        store_pixel(out, stats, p, result, m)
