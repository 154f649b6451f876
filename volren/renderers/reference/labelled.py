"""Reference ray integration of label volumes on uniform grids (the model of `volren.model.labels`).

Why: with a label map every point blends the TFs of its cell's corner labels, so the plain
reference's per-piece exactness (one TF, linear on each piece) no longer holds; this is the
reference's own quadrature of that model, in float64 and refined until it converges, that label
paths of other renderers are measured against (Real-Time Volume Graphics, chapter 16).

How, per pixel ray:
1. Clip and walk the grid as the plain path does (`volren.kernels.box_clipping.clip_box`,
   `volren.kernels.clip_planes.clip_entry`, `uniform.build_intervals`: one interval per cell, the
   trilinear scalar as a cubic in the ray parameter, cells with a non-finite corner dropped).
2. Per interval, the cell's eight corner classes (`label_classes.class_map`). A cell whose
   corners are all hidden is dropped; where they agree, that class alone with weight 1 (the fast
   path); else each visible class's weight w_c, the trilinear interpolant of the indicator
   "the corner's class is c", is a cubic along the ray too (`uniform.trilinear_cubic`).
3. Cuts: where s crosses a breakpoint of any class of the cell (`ray_integral`'s exact roots on
   the cubic's monotone spans), so that on every piece each class's TF is linear in s and the
   integrand is smooth. The level-0 pieces are those of the plain path (`refinement.level0_pieces`:
   steps of h0 intersected with the cuts).
4. Level L cuts every level-0 piece into 2^L equal parts; each part of length l is integrated in
   exact-exponential form at its midpoint u: tau = sum_c w_c(u) tau_c(s(u)),
   q = sum_c w_c(u) tau_c(s(u)) c_c(s(u)), alpha = 1 - exp(-tau l), colour q / tau, composited
   front to back (premultiplied, over black). The midpoint rule is second order on smooth
   pieces, so the levels converge as h^2 and `refinement.converged` stops them the same way;
   a ray stops early when its transmittance drops below 1e-9.
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

#: Most distinct classes in a cell: one per corner.
MAX_CELL_CLASSES = 8


@njit(nogil=True, cache=True)
def classify_intervals(o, d, grid, classes_at, ta, tb, P, m, K, W, nk):
    """The classes of the m intervals of one ray (`build_intervals`' cells) and their weight
    cubics: class K[k, n] has weight W[k, n] . (1, u, u^2, u^3), n < nk[k]. Intervals whose
    corners are all hidden are dropped, the others moved to the front; returns their number."""
    V, org, sp = grid.values, grid.origin, grid.spacing
    nz, ny, nx = V.shape
    dims = (nx, ny, nz)
    cell = np.zeros(3, np.int64)
    loc = np.zeros(3)
    rate = np.zeros(3)
    corners = np.empty(8, np.int32)
    indicator = np.empty(8)
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
        corners[0] = classes_at[kk, j, i]
        corners[1] = classes_at[kk, j, i + 1]
        corners[2] = classes_at[kk, j + 1, i]
        corners[3] = classes_at[kk, j + 1, i + 1]
        corners[4] = classes_at[kk + 1, j, i]
        corners[5] = classes_at[kk + 1, j, i + 1]
        corners[6] = classes_at[kk + 1, j + 1, i]
        corners[7] = classes_at[kk + 1, j + 1, i + 1]
        n = 0
        same = True
        for c in range(1, 8):
            if corners[c] != corners[0]:
                same = False
        if same:
            if corners[0] >= 0:
                K[kept, 0] = corners[0]
                W[kept, 0, 0] = 1.0
                W[kept, 0, 1] = 0.0
                W[kept, 0, 2] = 0.0
                W[kept, 0, 3] = 0.0
                n = 1
        else:
            for c in range(8):
                cls = corners[c]
                if cls < 0:
                    continue
                seen = False
                for e in range(n):
                    if K[kept, e] == cls:
                        seen = True
                if seen:
                    continue
                for e in range(8):
                    indicator[e] = 1.0 if corners[e] == cls else 0.0
                K[kept, n] = cls
                trilinear_cubic((indicator[0], indicator[1], indicator[2], indicator[3], indicator[4], indicator[5],
                                 indicator[6], indicator[7]), (loc[0], loc[1], loc[2]), (rate[0], rate[1], rate[2]),
                                W[kept, n])  # fmt: skip
                n += 1
        if n == 0:
            continue
        nk[kept] = n
        ta[kept] = ta[k]
        tb[kept] = tb[k]
        for e in range(4):
            P[kept, e] = P[k, e]
        kept += 1
    return kept


@njit(nogil=True, cache=True)
def _cuts_of(P, K, nk, k, length, classes, out):
    """The cut points of interval k (every class's breakpoint crossings, the cubic's critical
    points, its length), sorted into out when it holds them all; returns their count."""
    n = 0
    for e in range(nk[k]):
        c = K[k, e]
        bp = classes.cuts[classes.cut_offsets[c] : classes.cut_offsets[c + 1]]
        part = out[n:] if n < out.shape[0] else out[:0]
        n += _interval_cuts(P[k], length, bp, part)
    if n <= out.shape[0] and nk[k] > 1:
        out[:n].sort()
    return n


@njit(nogil=True, cache=True)
def label_cuts(ta, tb, P, K, nk, m, classes):
    """CSR of the sorted cut points of every interval: (offsets (m + 1), cuts)."""
    offsets = np.zeros(m + 1, np.int64)
    empty = np.empty(0)
    for k in range(m):
        length = tb[k] - ta[k]
        count = 0
        if length > 0.0:
            count = _cuts_of(P, K, nk, k, length, classes, empty)
        offsets[k + 1] = offsets[k] + count
    cuts = np.empty(offsets[m])
    for k in range(m):
        length = tb[k] - ta[k]
        if length > 0.0:
            _cuts_of(P, K, nk, k, length, classes, cuts[offsets[k] : offsets[k + 1]])
    return offsets, cuts


@njit(nogil=True, cache=True)
def _label_level(ta, tb, P, K, W, nk, m, pieces, level, classes):
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
        c = P[k]
        u0 = 0.0
        for e in range(starts[k], starts[k + 1]):
            u1 = ends[e]
            sub = (u1 - u0) / parts
            for q in range(parts):
                um = u0 + (q + 0.5) * sub
                s = cubic(c, um)
                tau = 0.0
                qr = 0.0
                qg = 0.0
                qb = 0.0
                for n in range(nk[k]):
                    w = min(max(cubic(W[k, n], um), 0.0), 1.0)
                    if w == 0.0:
                        continue
                    t, r, g, b = class_sample(classes, K[k, n], s)
                    wt = w * t
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
def integrate_labelled_ray(ta, tb, P, K, W, nk, m, classes, quad):
    """RGBA of one ray over its classified intervals, refined until two levels agree to the
    `Quadrature` quad's tolerance: (r, g, b, a, samples, level, converged, cap hits)."""
    if m == 0:
        return 0.0, 0.0, 0.0, 0.0, 0, 0, True, 0
    _, h0, tol, max_levels = quad
    offsets, cuts = label_cuts(ta, tb, P, K, nk, m, classes)
    pieces = level0_pieces(ta, tb, m, offsets, cuts, h0)
    pr = pg = pb = pa = 0.0
    samples = 0
    last = math.inf
    for level in range(max_levels):
        cr, cg, cb, ca, n = _label_level(ta, tb, P, K, W, nk, m, pieces, level, classes)
        change = max(abs(cr - pr), abs(cg - pg), abs(cb - pb), abs(ca - pa))
        pr, pg, pb, pa = cr, cg, cb, ca
        samples += n
        if level > 0:
            if converged(level, change, last, tol):
                return pr, pg, pb, pa, samples, level, True, 0
            last = change
    return pr, pg, pb, pa, samples, max_levels - 1, False, 0


@njit(nogil=True, parallel=True, cache=True)
def render_labelled(orig, dirs, tfar, grid, classes_at, classes, quad, out, stats):
    """One block of rays (origins, directions, far-plane parameters) through the `GridBox` grid
    whose points have the classes `classes_at` (-1 hidden) of the `PackedClasses` classes,
    composited as the `Quadrature` quad says: out (n, 4) float64 RGBA; stats (n, 5) = samples,
    level, unconverged, subdivision cap hits (none here), intervals (cells crossed)."""
    n = orig.shape[0]
    nz, ny, nx = grid.values.shape
    lo, hi = grid.lo, grid.hi
    cap = nx + ny + nz + 4
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
        K = np.empty((m, MAX_CELL_CLASSES), np.int32)
        W = np.empty((m, MAX_CELL_CLASSES, 4))
        nk = np.zeros(m, np.int64)
        kept = classify_intervals((ox, oy, oz), (dx, dy, dz), grid, classes_at, ta, tb, P, m, K, W, nk)
        result = integrate_labelled_ray(ta, tb, P, K, W, nk, kept, classes, quad)
        store_pixel(out, stats, p, result, m)
