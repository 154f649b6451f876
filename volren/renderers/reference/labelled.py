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
4. The classes are the terms of `mixture.integrate_mixture_ray` (each on the cell's one scalar,
   weighted by its indicator's cubic): tau = sum_c w_c(u) tau_c(s(u)),
   q = sum_c w_c(u) tau_c(s(u)) c_c(s(u)), refined level by level until it converges.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from volren.renderers.reference.mixture import integrate_mixture_ray
from volren.renderers.reference.ray_integral import store_pixel
from volren.renderers.reference.uniform import build_intervals, cell_frame, corners, ray_span, trilinear_cubic

#: Most distinct classes in a cell: one per corner.
MAX_CELL_CLASSES = 8


@njit(nogil=True, cache=True)
def classify_intervals(o, d, grid, classes_at, ta, tb, P, m, S, W, K, nk):
    """The classes of the m intervals of one ray (`build_intervals`' cells) as `mixture` terms:
    class K[k, n] on the scalar S[k, n] (the cell's cubic P) with weight W[k, n] (the cubic of
    its corners' indicator), n < nk[k]. Intervals whose corners are all hidden are dropped, the
    others moved to the front; returns their number."""
    org, sp = grid.origin, grid.spacing
    nz, ny, nx = grid.values.shape
    dims = (nx, ny, nz)
    cell = np.zeros(3, np.int64)
    loc = np.zeros(3)
    rate = np.zeros(3)
    indicator = np.empty(8)
    kept = 0
    for k in range(m):
        cell_frame(o, d, org, sp, dims, ta[k], tb[k], cell, loc, rate)
        at = corners(classes_at, cell[2], cell[1], cell[0])
        n = 0
        same = True
        for c in range(1, 8):
            if at[c] != at[0]:
                same = False
        if same:
            if at[0] >= 0:
                K[kept, 0] = at[0]
                W[kept, 0, 0] = 1.0
                W[kept, 0, 1] = 0.0
                W[kept, 0, 2] = 0.0
                W[kept, 0, 3] = 0.0
                n = 1
        else:
            for c in range(8):
                cls = at[c]
                if cls < 0:
                    continue
                seen = False
                for e in range(n):
                    if K[kept, e] == cls:
                        seen = True
                if seen:
                    continue
                for e in range(8):
                    indicator[e] = 1.0 if at[e] == cls else 0.0
                K[kept, n] = cls
                trilinear_cubic((indicator[0], indicator[1], indicator[2], indicator[3], indicator[4], indicator[5],
                                 indicator[6], indicator[7]), (loc[0], loc[1], loc[2]), (rate[0], rate[1], rate[2]),
                                W[kept, n])  # fmt: skip
                n += 1
        if n == 0:
            continue
        for e in range(n):
            for q in range(4):
                S[kept, e, q] = P[k, q]
        nk[kept] = n
        ta[kept] = ta[k]
        tb[kept] = tb[k]
        kept += 1
    return kept


@njit(nogil=True, parallel=True, cache=True)
def render_labelled(orig, dirs, tfar, grid, classes_at, classes, quad, out, stats):
    """One block of rays (origins, directions, far-plane parameters) through the `GridBox` grid
    whose points have the classes `classes_at` (-1 hidden) of the `PackedClasses` classes,
    composited as the `Quadrature` quad says: out (n, 4) float64 RGBA; stats (n, 5) = samples,
    level, unconverged, subdivision cap hits (none here), intervals (cells crossed)."""
    n = orig.shape[0]
    nz, ny, nx = grid.values.shape
    cap = nx + ny + nz + 4
    scale = np.ones(classes.units.shape[0])
    for p in prange(n):
        o, d, t0, t1, _ = ray_span(orig, dirs, tfar, p, grid, out, stats)
        if not (t1 > t0):
            continue
        ta = np.empty(cap)
        tb = np.empty(cap)
        P = np.empty((cap, 4))
        G = np.empty((0, 3, 4))
        m = build_intervals(o, d, t0, t1, grid, False, ta, tb, P, G)
        K = np.empty((m, MAX_CELL_CLASSES), np.int32)
        S = np.empty((m, MAX_CELL_CLASSES, 4))
        W = np.empty((m, MAX_CELL_CLASSES, 4))
        nk = np.zeros(m, np.int64)
        kept = classify_intervals(o, d, grid, classes_at, ta, tb, P, m, S, W, K, nk)
        result = integrate_mixture_ray(ta, tb, S, W, K, nk, kept, classes, scale, quad)
        store_pixel(out, stats, p, result, m)
