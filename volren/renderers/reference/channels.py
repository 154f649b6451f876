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
4. Level L cuts every level-0 piece into 2^L equal parts; each part of length l is integrated in
   exact-exponential form at its midpoint u: tau = sum_c w_c tau_c(s_c(u)), q = sum_c w_c
   tau_c(s_c(u)) c_c(s_c(u)), alpha = 1 - exp(-tau l), colour q / tau, composited front to back
   (premultiplied, over black), as `labelled` does. The midpoint rule is second order on smooth
   pieces, so `refinement.converged` stops the levels the same way; a ray stops early when its
   transmittance drops below 1e-9.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from volren.kernels.box_clipping import clip_box
from volren.kernels.clip_planes import clip_entry
from volren.renderers.reference.label_classes import class_sample
from volren.renderers.reference.ray_integral import MIN_TRANSMITTANCE, _interval_cuts, cubic, store_pixel
from volren.renderers.reference.refinement import converged, level0_pieces
from volren.renderers.reference.uniform import build_intervals, trilinear_cubic


@njit(nogil=True, cache=True)
def channel_intervals(o, d, grid, values, drawn, ta, tb, m, C, S, nc):
    """The drawn channels of the m intervals of one ray (`build_intervals`' cells) and their scalar
    cubics: drawn channel C[k, n] (an index into `drawn`, whose entries index values[c, k, j, i])
    has the value S[k, n] . (1, u, u^2, u^3), n < nc[k]. A channel with a non-finite corner is left
    out of its cell, a cell with no channel left is dropped, the others are moved to the front;
    returns their number."""
    org, sp = grid.origin, grid.spacing
    nz, ny, nx = values.shape[1], values.shape[2], values.shape[3]
    dims = (nx, ny, nz)
    cell = np.zeros(3, np.int64)
    loc = np.zeros(3)
    rate = np.zeros(3)
    v = np.empty(8)
    kept = 0
    for k in range(m):
        t = ta[k]
        tm = 0.5 * (ta[k] + tb[k])
        for a in range(3):  # the cell and local coordinates exactly as build_intervals takes them
            u = (o[a] + tm * d[a] - org[a]) / sp[a]
            c = min(max(int(math.floor(u)), 0), dims[a] - 2)
            cell[a] = c
            loc[a] = (o[a] + t * d[a] - org[a]) / sp[a] - c
            rate[a] = d[a] / sp[a]
        i, j, kk = cell[0], cell[1], cell[2]
        n = 0
        for e in range(drawn.shape[0]):
            V = values[drawn[e]]
            v[0] = V[kk, j, i]
            v[1] = V[kk, j, i + 1]
            v[2] = V[kk, j + 1, i]
            v[3] = V[kk, j + 1, i + 1]
            v[4] = V[kk + 1, j, i]
            v[5] = V[kk + 1, j, i + 1]
            v[6] = V[kk + 1, j + 1, i]
            v[7] = V[kk + 1, j + 1, i + 1]
            finite = True
            for q in range(8):
                if not math.isfinite(v[q]):
                    finite = False
            if not finite:
                continue
            C[kept, n] = e
            trilinear_cubic((v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7]), (loc[0], loc[1], loc[2]),
                            (rate[0], rate[1], rate[2]), S[kept, n])  # fmt: skip
            n += 1
        if n == 0:
            continue
        nc[kept] = n
        ta[kept] = ta[k]
        tb[kept] = tb[k]
        kept += 1
    return kept


@njit(nogil=True, cache=True)
def _cuts_of(S, C, nc, k, length, tfs, out):
    """The cut points of interval k (every channel's breakpoint crossings and critical points, its
    length), sorted into out when it holds them all; returns their count."""
    n = 0
    for e in range(nc[k]):
        c = C[k, e]
        bp = tfs.cuts[tfs.cut_offsets[c] : tfs.cut_offsets[c + 1]]
        part = out[n:] if n < out.shape[0] else out[:0]
        n += _interval_cuts(S[k, e], length, bp, part)
    if n <= out.shape[0] and nc[k] > 1:
        out[:n].sort()
    return n


@njit(nogil=True, cache=True)
def channel_cuts(ta, tb, S, C, nc, m, tfs):
    """CSR of the sorted cut points of every interval: (offsets (m + 1), cuts)."""
    offsets = np.zeros(m + 1, np.int64)
    empty = np.empty(0)
    for k in range(m):
        length = tb[k] - ta[k]
        count = 0
        if length > 0.0:
            count = _cuts_of(S, C, nc, k, length, tfs, empty)
        offsets[k + 1] = offsets[k] + count
    cuts = np.empty(offsets[m])
    for k in range(m):
        length = tb[k] - ta[k]
        if length > 0.0:
            _cuts_of(S, C, nc, k, length, tfs, cuts[offsets[k] : offsets[k + 1]])
    return offsets, cuts


@njit(nogil=True, cache=True)
def _channel_level(ta, tb, S, C, nc, m, pieces, level, tfs, weights):
    """One level of the composite: every level-0 piece cut into 2^level equal parts, each
    integrated at its midpoint in exact-exponential form; (r, g, b, a, samples)."""
    starts, ends = pieces
    parts = 1 << level
    T = 1.0
    cr = 0.0
    cg = 0.0
    cb = 0.0
    samples = 0
    for k in range(m):
        if not (tb[k] - ta[k] > 0.0):
            continue
        u0 = 0.0
        for e in range(starts[k], starts[k + 1]):
            u1 = ends[e]
            sub = (u1 - u0) / parts
            for q in range(parts):
                um = u0 + (q + 0.5) * sub
                tau = 0.0
                qr = 0.0
                qg = 0.0
                qb = 0.0
                for n in range(nc[k]):
                    c = C[k, n]
                    t, r, g, b = class_sample(tfs, c, cubic(S[k, n], um))
                    wt = weights[c] * t
                    tau += wt
                    qr += wt * r
                    qg += wt * g
                    qb += wt * b
                samples += 1
                if not (tau > 0.0):
                    continue
                od = tau * sub
                weight = T * -math.expm1(-od) / tau
                cr += weight * qr
                cg += weight * qg
                cb += weight * qb
                T *= math.exp(-od)
                if T < MIN_TRANSMITTANCE:
                    return cr, cg, cb, 1.0 - T, samples
            u0 = u1
    return cr, cg, cb, 1.0 - T, samples


@njit(nogil=True, cache=True)
def integrate_channel_ray(ta, tb, S, C, nc, m, tfs, weights, quad):
    """RGBA of one ray over its channel intervals, refined until two levels agree to the
    `Quadrature` quad's tolerance: (r, g, b, a, samples, level, converged, cap hits)."""
    if m == 0:
        return 0.0, 0.0, 0.0, 0.0, 0, 0, True, 0
    _, h0, tol, max_levels = quad
    offsets, cuts = channel_cuts(ta, tb, S, C, nc, m, tfs)
    pieces = level0_pieces(ta, tb, m, offsets, cuts, h0)
    pr = pg = pb = pa = 0.0
    samples = 0
    last = math.inf
    for level in range(max_levels):
        cr, cg, cb, ca, n = _channel_level(ta, tb, S, C, nc, m, pieces, level, tfs, weights)
        change = max(abs(cr - pr), abs(cg - pg), abs(cb - pb), abs(ca - pa))
        pr, pg, pb, pa = cr, cg, cb, ca
        samples += n
        if level > 0:
            if converged(level, change, last, tol):
                return pr, pg, pb, pa, samples, level, True, 0
            last = change
    return pr, pg, pb, pa, samples, max_levels - 1, False, 0


@njit(nogil=True, parallel=True, cache=True)
def render_channels(orig, dirs, tfar, grid, values, drawn, tfs, weights, quad, out, stats):
    """One block of rays (origins, directions, far-plane parameters) through the `GridBox` grid
    (its values only give the walk its cells) with the channels values[c, k, j, i], of which those
    in `drawn` are drawn with the `PackedClasses` tfs and the weights (both indexed like `drawn`),
    composited as the `Quadrature` quad says: out (n, 4) float64 RGBA; stats (n, 5) = samples,
    level, unconverged, subdivision cap hits (none here), intervals (cells crossed)."""
    n = orig.shape[0]
    nz, ny, nx = grid.values.shape
    lo, hi = grid.lo, grid.hi
    cap = nx + ny + nz + 4
    width = drawn.shape[0]
    for p in prange(n):
        ox, oy, oz = orig[p, 0], orig[p, 1], orig[p, 2]
        dx, dy, dz = dirs[p, 0], dirs[p, 1], dirs[p, 2]
        t0, t1 = clip_box(ox, oy, oz, dx, dy, dz, lo, hi, 0.0, tfar[p])
        t0, t1, _ = clip_entry(ox, oy, oz, dx, dy, dz, grid.planes, t0, t1)
        for c in range(4):
            out[p, c] = 0.0
        for c in range(5):
            stats[p, c] = 0
        if not (t1 > t0):
            continue
        ta = np.empty(cap)
        tb = np.empty(cap)
        P = np.empty((cap, 4))
        G = np.empty((0, 3, 4))
        m = build_intervals((ox, oy, oz), (dx, dy, dz), t0, t1, grid, False, ta, tb, P, G)
        C = np.empty((m, width), np.int64)
        S = np.empty((m, width, 4))
        nc = np.zeros(m, np.int64)
        kept = channel_intervals((ox, oy, oz), (dx, dy, dz), grid, values, drawn, ta, tb, m, C, S, nc)
        result = integrate_channel_ray(ta, tb, S, C, nc, kept, tfs, weights, quad)
        store_pixel(out, stats, p, result, m)
