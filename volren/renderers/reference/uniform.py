"""Reference ray integration through a uniform grid with trilinear reconstruction.

Why: the uniform path must produce the exact integral of DESIGN.md's model over the trilinear
interpolant, independently of any sampling choice a GPU renderer makes.

How, per pixel ray (origin on the near plane, unit direction d):
1. Clip the ray to the box of the point bounds with the slab test, to [0, t_far] (the near and
   far clipping planes, as a GPU ray caster does) and to the clip region's planes. Nothing outside
   the box is ever sampled.
2. Walk the cells the ray crosses: the crossings with the grid planes x = x_i, y = y_j, z = z_k
   are merged in order, each crossing time computed from its plane index (no accumulated
   stepping error). The cell of an interval is taken from its midpoint, so rays running exactly
   along grid planes are handled like any other.
3. Inside a cell the trilinear interpolant restricted to the ray is an exact cubic in the ray
   parameter; its four coefficients are expanded from the eight corner values (float64). A cell
   with a non-finite corner is transparent, which is what "interpolated values that are not
   finite are transparent" means for trilinear reconstruction, and it drops out of max / min /
   average as well.
4. When shading, the gradient at the eight corners (central differences in world units, one-sided
   at the borders) is interpolated the same way: three more cubics.
5. `refinement.integrate_ray` does the adaptive quadrature (or the exact max / min / average), with
   a 1D TF (`ray_integral`) or a 2D one (`tf2d`, which needs the gradient cubics always).

Cell boundaries are the only places where the trilinear interpolant has kinks, so splitting the
ray there keeps the quadrature at second order everywhere. The kernel is
``@njit(nogil=True, parallel=True)`` with a prange over the pixels of one block of rows.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from volren.kernels.box_clipping import clip_box
from volren.kernels.clip_planes import clip_entry
from volren.kernels.cut_faces import cut_face
from volren.renderers.reference.ray_inputs import RayIntervals
from volren.renderers.reference.ray_integral import store_pixel
from volren.renderers.reference.refinement import integrate_ray


@njit(nogil=True, cache=True)
def trilinear_cubic(corners, start, rate, out):
    """Coefficients (in u) of the trilinear interpolant along x = x0 + ax u, y = ..., z = ...
    with start = (x0, y0, z0), rate = (ax, ay, az).

    Local cell coordinates: corner vXYZ sits at (X, Y, Z) in {0, 1}^3; corners = (v000, v100,
    v010, v110, v001, v101, v011, v111).
    """
    v000, v100, v010, v110, v001, v101, v011, v111 = corners
    x0, y0, z0 = start
    ax, ay, az = rate
    cx = v100 - v000
    cy = v010 - v000
    cz = v001 - v000
    cxy = v110 - v100 - v010 + v000
    cxz = v101 - v100 - v001 + v000
    cyz = v011 - v010 - v001 + v000
    cxyz = v111 - v110 - v101 - v011 + v100 + v010 + v001 - v000
    out[0] = (
        v000
        + cx * x0
        + cy * y0
        + cz * z0
        + cxy * x0 * y0
        + cxz * x0 * z0
        + cyz * y0 * z0
        + cxyz * x0 * y0 * z0
    )
    out[1] = (
        cx * ax
        + cy * ay
        + cz * az
        + cxy * (x0 * ay + ax * y0)
        + cxz * (x0 * az + ax * z0)
        + cyz * (y0 * az + ay * z0)
        + cxyz * (ax * y0 * z0 + x0 * ay * z0 + x0 * y0 * az)
    )
    out[2] = (
        cxy * ax * ay + cxz * ax * az + cyz * ay * az + cxyz * (ax * ay * z0 + ax * y0 * az + x0 * ay * az)
    )
    out[3] = cxyz * ax * ay * az


@njit(nogil=True, cache=True)
def cell_frame(o, d, org, sp, dims, t, tn, cell, loc, rate):
    """The cell that the ray piece [t, tn] crosses (its midpoint's, clamped to the grid), the
    piece's start in the cell's local coordinates and their rates per unit t: the frame in which
    `trilinear_cubic` turns the cell's corners into cubics along the piece."""
    tm = 0.5 * (t + tn)
    for a in range(3):
        u = (o[a] + tm * d[a] - org[a]) / sp[a]
        c = int(math.floor(u))
        c = min(max(c, 0), dims[a] - 2)
        cell[a] = c
        loc[a] = (o[a] + t * d[a] - org[a]) / sp[a] - c
        rate[a] = d[a] / sp[a]


@njit(nogil=True, cache=True)
def corners(V, k, j, i):
    """The eight corners of cell (k, j, i) of V[z, y, x] in `trilinear_cubic`'s order."""
    return (V[k, j, i], V[k, j, i + 1], V[k, j + 1, i], V[k, j + 1, i + 1],
            V[k + 1, j, i], V[k + 1, j, i + 1], V[k + 1, j + 1, i], V[k + 1, j + 1, i + 1])  # fmt: skip


@njit(nogil=True, cache=True)
def ray_span(orig, dirs, tfar, p, grid, out, stats):
    """Ray p's origin, direction, its span (t0, t1) inside the `GridBox` grid's box and clip planes
    and the plane it enters through (-1: none); clears its pixel and statistics."""
    ox, oy, oz = orig[p, 0], orig[p, 1], orig[p, 2]
    dx, dy, dz = dirs[p, 0], dirs[p, 1], dirs[p, 2]
    t0, t1 = clip_box(ox, oy, oz, dx, dy, dz, grid.lo, grid.hi, 0.0, tfar[p])
    t0, t1, entering = clip_entry(ox, oy, oz, dx, dy, dz, grid.planes, t0, t1)
    for c in range(4):
        out[p, c] = 0.0
    for c in range(5):
        stats[p, c] = 0
    return (ox, oy, oz), (dx, dy, dz), t0, t1, entering


@njit(nogil=True, cache=True)
def _diff(V, k, j, i, axis, h):
    """d s / d axis at grid point (k, j, i): central inside, one-sided at the borders."""
    if axis == 0:
        n = V.shape[2]
        if i == 0:
            return (V[k, j, 1] - V[k, j, 0]) / h
        if i == n - 1:
            return (V[k, j, n - 1] - V[k, j, n - 2]) / h
        return (V[k, j, i + 1] - V[k, j, i - 1]) / (2.0 * h)
    if axis == 1:
        n = V.shape[1]
        if j == 0:
            return (V[k, 1, i] - V[k, 0, i]) / h
        if j == n - 1:
            return (V[k, n - 1, i] - V[k, n - 2, i]) / h
        return (V[k, j + 1, i] - V[k, j - 1, i]) / (2.0 * h)
    n = V.shape[0]
    if k == 0:
        return (V[1, j, i] - V[0, j, i]) / h
    if k == n - 1:
        return (V[n - 1, j, i] - V[n - 2, j, i]) / h
    return (V[k + 1, j, i] - V[k - 1, j, i]) / (2.0 * h)


@njit(nogil=True, cache=True)
def build_intervals(o, d, t_in, t_out, grid, shading, ta, tb, P, G):
    """Fill the per-cell intervals of one ray (origin o, direction d: (x, y, z)) through the
    `GridBox` grid on [t_in, t_out] (front to back, `RayIntervals`' arrays); returns their number."""
    V, org, sp = grid.values, grid.origin, grid.spacing
    nz, ny, nx = V.shape
    dims = (nx, ny, nz)
    cap = ta.shape[0]
    idx = np.zeros(3, np.int64)
    step = np.zeros(3, np.int64)
    tnext = np.full(3, np.inf)
    for a in range(3):
        if d[a] != 0.0:
            u = (o[a] + t_in * d[a] - org[a]) / sp[a]
            if d[a] > 0.0:
                idx[a] = int(math.floor(u)) + 1
                step[a] = 1
            else:
                idx[a] = int(math.ceil(u)) - 1
                step[a] = -1
            tnext[a] = (org[a] + idx[a] * sp[a] - o[a]) / d[a]
    cell = np.zeros(3, np.int64)
    loc = np.zeros(3)
    rate = np.zeros(3)
    t = t_in
    m = 0
    while True:
        tn = min(min(tnext[0], tnext[1]), min(tnext[2], t_out))
        if tn > t:
            if m < cap:
                cell_frame(o, d, org, sp, dims, t, tn, cell, loc, rate)
                i = cell[0]
                j = cell[1]
                k = cell[2]
                v000, v100, v010, v110, v001, v101, v011, v111 = corners(V, k, j, i)
                finite = (
                    math.isfinite(v000) and math.isfinite(v100) and math.isfinite(v010) and math.isfinite(v110)
                    and math.isfinite(v001) and math.isfinite(v101) and math.isfinite(v011) and math.isfinite(v111)
                )  # fmt: skip
                if finite:
                    ta[m] = t
                    tb[m] = tn
                    trilinear_cubic((v000, v100, v010, v110, v001, v101, v011, v111), (loc[0], loc[1], loc[2]),
                                    (rate[0], rate[1], rate[2]), P[m])  # fmt: skip
                    if shading:
                        for axis in range(3):
                            h = sp[axis]
                            trilinear_cubic(
                                (
                                    _diff(V, k, j, i, axis, h),
                                    _diff(V, k, j, i + 1, axis, h),
                                    _diff(V, k, j + 1, i, axis, h),
                                    _diff(V, k, j + 1, i + 1, axis, h),
                                    _diff(V, k + 1, j, i, axis, h),
                                    _diff(V, k + 1, j, i + 1, axis, h),
                                    _diff(V, k + 1, j + 1, i, axis, h),
                                    _diff(V, k + 1, j + 1, i + 1, axis, h),
                                ),
                                (loc[0], loc[1], loc[2]), (rate[0], rate[1], rate[2]), G[m, axis],
                            )  # fmt: skip
                    m += 1
            t = tn
        if tn >= t_out:
            break
        for a in range(3):
            while tnext[a] <= tn:
                idx[a] += step[a]
                tnext[a] = (org[a] + idx[a] * sp[a] - o[a]) / d[a]
    return m


@njit(nogil=True, cache=True)
def value_at(grid, x, y, z):
    """The trilinear interpolant of the `GridBox` grid at world point (x, y, z) inside its box; NaN
    where a corner of the cell is not finite."""
    V, org, sp = grid.values, grid.origin, grid.spacing
    nz, ny, nx = V.shape
    u = min(max((x - org[0]) / sp[0], 0.0), nx - 1.0)
    v = min(max((y - org[1]) / sp[1], 0.0), ny - 1.0)
    w = min(max((z - org[2]) / sp[2], 0.0), nz - 1.0)
    i = min(int(u), nx - 2)
    j = min(int(v), ny - 2)
    k = min(int(w), nz - 2)
    fx, fy, fz = u - i, v - j, w - k
    c00 = V[k, j, i] + fx * (V[k, j, i + 1] - V[k, j, i])
    c10 = V[k, j + 1, i] + fx * (V[k, j + 1, i + 1] - V[k, j + 1, i])
    c01 = V[k + 1, j, i] + fx * (V[k + 1, j, i + 1] - V[k + 1, j, i])
    c11 = V[k + 1, j + 1, i] + fx * (V[k + 1, j + 1, i + 1] - V[k + 1, j + 1, i])
    return (c00 + fy * (c10 - c00)) + fz * ((c01 + fy * (c11 - c01)) - (c00 + fy * (c10 - c00)))


@njit(nogil=True, parallel=True, cache=True)
def render_uniform(orig, dirs, tfar, grid, tf, tf2d, spar, quad, out, stats):
    """One block of rays (origins, directions, far-plane parameters) through the `GridBox` grid,
    integrated as the `Quadrature` quad says with the `ShadeParams` spar: out (n, 4) float64 RGBA;
    stats (n, 5) = samples, level, unconverged, subdivision cap hits, intervals. One of `tf` (1D)
    and `tf2d` (2D, composite) is None."""
    n = orig.shape[0]
    nz, ny, nx = grid.values.shape
    cap = nx + ny + nz + 4
    gradients = spar.on  # shading
    if tf2d is not None:
        gradients = True  # |grad s| is the 2D TF's second axis
    for p in prange(n):
        o, d, t0, t1, entering = ray_span(orig, dirs, tfar, p, grid, out, stats)
        if not (t1 > t0):
            continue
        ox, oy, oz = o
        dx, dy, dz = d
        if grid.cap and entering >= 0 and tf is not None:  # an opaque cut face first
            n = grid.planes[entering]
            s = value_at(grid, ox + t0 * dx, oy + t0 * dy, oz + t0 * dz)
            r, g, b, visible = cut_face(tf, s, n[0], n[1], n[2], spar, dx, dy, dz)
            if visible:
                out[p, 0], out[p, 1], out[p, 2], out[p, 3] = r, g, b, 1.0
                continue
        ta = np.empty(cap)
        tb = np.empty(cap)
        P = np.empty((cap, 4))
        G = np.empty((cap if gradients else 0, 3, 4))
        m = build_intervals(o, d, t0, t1, grid, gradients, ta, tb, P, G)
        result = integrate_ray(RayIntervals(ta, tb, P, G, m), quad, tf, tf2d, spar, dx, dy, dz)
        store_pixel(out, stats, p, result, m)
