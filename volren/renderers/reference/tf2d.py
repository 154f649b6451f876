"""Reference integration of a 2D transfer function (value x gradient magnitude) on uniform grids.

Why: a 2D TF's integrand along a ray is not piecewise linear in s (widgets are Gaussian,
triangular or box-shaped over (s, |grad s|), and |grad s| varies along the ray on its own), so the
1D path's exact cuts and exact mean extinction do not apply. This module integrates it by
refinement instead, with the same exact-exponential pieces, inside the 1D path's scaffolding
(`refinement.integrate_ray`: the cuts' table, the levels and the rule that stops them; the rays'
intervals come from `uniform.render_uniform`), and leaves the 1D quadrature (`ray_integral`) as it is.

The TF is evaluated exactly as `TransferFunction2D.sample` defines it (`eval_tf2d`: the widget
formulas, a 1d widget's points as `tf_eval.interp` evaluates a 1D TF's, clamping to the TF's
rectangle, a = 1 - prod(1 - a_i), c = sum a_i c_i / sum a_i), at
s = the trilinear interpolant and g = |grad s|, where grad s is exactly the gradient the shading
uses: central differences at the grid points in world units (one-sided at the borders),
interpolated trilinearly like the scalars (`uniform.build_intervals` with its gradient cubics on).
Non-finite s or g (next to NaN voxels) is transparent, like `sample`.

Per ray (composite only; the capabilities offer no other blend mode with a 2D TF):
1. Cuts, per interval (cell): critical points of s and crossings of the value edges of the box
   widgets, of the triangles' centre lines s = s0 and of the 1d widgets' control points (exact
   roots, `ray_integral._interval_cuts`); crossings of |grad s| with the box and 1d widgets'
   gradient edges and the triangles' gradient_max
   (the opacity jumps there), and with the no-shading threshold when shading (the colour jumps
   there); crossings of the triangles' edges |s - s0| = (w / gm) |grad s|; and, when the TF has
   a Gaussian or a triangle, the critical points of |grad s|. Along the interval |grad s|^2 and
   (s - s0)^2 - (w / gm)^2 |grad s|^2 are polynomials of degree 6, so all of these are found
   (`_poly_crossings`: the roots of each derivative bound the monotone spans of the one before
   it). Edges outside the TF's rectangle are dropped (the TF is clamped, so nothing jumps there).
   Between two cuts the integrand is smooth apart from the clamp at the rectangle's edges, s and
   |grad s| are monotone, and every box or triangle is either present throughout or absent.
2. The level-0 partition: interval k is split into ceil(len / h0) equal pieces intersected with
   the cuts (`refinement.level0_pieces`, shared with the 1D path); each piece is subdivided so that, for every widget whose support box (a Gaussian's
   to 6 standard deviations) meets the piece's span of (s, g) (exact, from its ends: both are
   monotone), s changes by at most FRACTION of the widget's value scale and g by at most
   FRACTION of its gradient scale (Gaussian: its standard deviations; triangle: its half-width
   at the piece's largest g, at least 1/64 of half_width, and gradient_max; box and 1d: none,
   they are constant and linear in s between cuts), and when shading the normal turns by at most SHADING_TURN; at most
   MAX_SUBDIVISION sub-pieces (hits counted).
3. Level L bisects every level-0 sub-piece L times (as in the 1D path).
4. A sub-piece of length l: tau from the TF at its midpoint, x = tau l, alpha = 1 - exp(-x),
   colour from the TF (shaded when shading is on) at the emission centre u_e = l (1/x - 1/(e^x-1))
   (the midpoint's colour where the TF is transparent at u_e), C += T alpha c, T *= exp(-x).
   Exact for homogeneous pieces; second order where the integrand is smooth.
5. Stop when T < MIN_TRANSMITTANCE; levels until two successive ones agree by the 1D path's rule
   (`refinement.integrate_ray`), with the change between two levels measured per channel as the
   sum over the intervals of the change of each interval's share of the pixel (`share_change`),
   so changes in different cells cannot cancel and stop a ray early by accident.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from volren.kernels.shading import shade
from volren.kernels.tf_eval import interp
from volren.model.preintegration.segment_math import emission_centre
from volren.model.transfer_function import MAX_OPACITY
from volren.model.transfer_function_2d import TransferFunction2D
from volren.renderers.reference.ray_integral import (
    FRACTION,
    MAX_SUBDIVISION,
    MIN_TRANSMITTANCE,
    SHADING_TURN,
    _interval_cuts,
    _normal_turn,
    cubic,
)

GAUSSIAN, TRIANGLE, BOX, PROFILE = 0, 1, 2, 3
_TYPES = {"gaussian": GAUSSIAN, "triangle": TRIANGLE, "box": BOX, "1d": PROFILE}
#: A Gaussian counts as present within this many standard deviations (exp(-18) ~ 1.5e-8).
GAUSSIAN_REACH = 6.0
#: A triangle's value scale near its apex is at least this fraction of its half_width.
TRIANGLE_MIN_SCALE = 1.0 / 64.0


class PackedTF2D(NamedTuple):
    """A 2D TF as the kernels read it (`pack_tf2d`)."""

    types: NDArray[np.int64]
    params: NDArray[np.float64]
    rgb: NDArray[np.float64]
    peak: NDArray[np.float64]
    rect: NDArray[np.float64]
    unit: float
    value_cuts: NDArray[np.float64]
    gradient_cuts: NDArray[np.float64]
    support: NDArray[np.float64]
    #: the 1d widgets' points (`_pack_profiles`)
    color_start: NDArray[np.int64]
    color_x: NDArray[np.float64]
    color_rgb: NDArray[np.float64]
    opacity_start: NDArray[np.int64]
    opacity_x: NDArray[np.float64]
    opacity_a: NDArray[np.float64]


def pack_tf2d(tf: TransferFunction2D) -> PackedTF2D:
    """The TF as arrays for the kernels:

    types (n,) int64        GAUSSIAN, TRIANGLE, BOX or PROFILE (1d) per widget
    params (n, 4)           gaussian (s0, g0, ws, wg); triangle (s0, w, gm, 0);
                            box (s_lo, s_hi, g_lo, g_hi); 1d (g_lo, g_hi, 0, 0)
    rgb (n, 3), peak (n,)   colour and peak opacity (a 1d widget's tint and opacity scale)
    rect (3,)               (lo, hi, gmax): the TF's rectangle, inputs are clamped to it
    unit                    opacity_unit_distance
    value_cuts              sorted box value edges and triangle centres inside (lo, hi)
    gradient_cuts           sorted box gradient edges and triangle tops inside (0, gmax)
    support (n, 4)          (s_min, s_max, g_min, g_max) outside which a widget is ~0
    color_start ... opacity_a  the 1d widgets' points (six arrays, `_pack_profiles`)
    """
    widgets = tf.widgets
    n = len(widgets)
    types = np.zeros(n, np.int64)
    params = np.zeros((n, 4))
    rgb = np.zeros((n, 3))
    peak = np.zeros(n)
    support = np.zeros((n, 4))
    lo, hi = tf.value_range
    gmax = tf.gradient_range[1]
    vcuts: list[float] = []
    gcuts: list[float] = []
    for i, w in enumerate(widgets):
        types[i] = _TYPES[w.type]
        rgb[i] = w.color
        peak[i] = w.opacity
        if w.type == "gaussian":
            (s0, g0), (ws, wg) = w.center, w.width  # type: ignore[misc]
            params[i] = (s0, g0, ws, wg)
            r = GAUSSIAN_REACH
            support[i] = (s0 - r * ws, s0 + r * ws, g0 - r * wg, g0 + r * wg)
        elif w.type == "triangle":
            s0, hw, gm = w.value, w.half_width, w.gradient_max
            params[i] = (s0, hw, gm, 0.0)
            support[i] = (s0 - hw, s0 + hw, 0.0, gm)  # type: ignore[operator]
            vcuts.append(s0)  # type: ignore[arg-type]  # a kink along the centre line
            gcuts.append(gm)  # type: ignore[arg-type]
        elif w.type == "box":
            (s_lo, s_hi), (g_lo, g_hi) = w.value_range, w.gradient_range  # type: ignore[misc]
            params[i] = (s_lo, s_hi, g_lo, g_hi)
            support[i] = (s_lo, s_hi, g_lo, g_hi)
            vcuts += [s_lo, s_hi]
            gcuts += [g_lo, g_hi]
        else:  # 1d: its kinks in value, its band's edges in gradient
            g_lo, g_hi = w.gradient_range  # type: ignore[misc]
            params[i] = (g_lo, g_hi, 0.0, 0.0)
            support[i] = (-math.inf, math.inf, g_lo, g_hi)
            vcuts += w.profile().breakpoints().tolist()
            gcuts += [g_lo, g_hi]
    value_cuts = np.unique(np.asarray([v for v in vcuts if lo < v < hi], dtype=np.float64))
    gradient_cuts = np.unique(np.asarray([g for g in gcuts if 0.0 < g < gmax], dtype=np.float64))
    rect = np.array([lo, hi, gmax], dtype=np.float64)
    return PackedTF2D(
        types,
        params,
        rgb,
        peak,
        rect,
        float(tf.opacity_unit_distance),
        value_cuts,
        gradient_cuts,
        support,
        *_pack_profiles(widgets),
    )


def _pack_profiles(widgets) -> tuple:
    """The 1d widgets' points, all widgets' in one array each (empty for the other types):
    (color_start (n + 1,), color_x, color_rgb (., 3), opacity_start (n + 1,), opacity_x, opacity_a);
    widget i's colour points are rows color_start[i]:color_start[i + 1]."""
    color = [np.asarray(w.color_points if w.type == "1d" else np.zeros((0, 4))) for w in widgets]
    opacity = [np.asarray(w.opacity_points if w.type == "1d" else np.zeros((0, 2))) for w in widgets]
    color_all = np.concatenate([np.zeros((0, 4)), *color]).astype(np.float64)
    opacity_all = np.concatenate([np.zeros((0, 2)), *opacity]).astype(np.float64)
    return (
        np.cumsum([0] + [len(c) for c in color]).astype(np.int64),
        np.ascontiguousarray(color_all[:, 0]),
        np.ascontiguousarray(color_all[:, 1:4]),
        np.cumsum([0] + [len(o) for o in opacity]).astype(np.int64),
        np.ascontiguousarray(opacity_all[:, 0]),
        np.ascontiguousarray(opacity_all[:, 1]),
    )


@njit(nogil=True, cache=True)
def _profile_opacity(tf, i, s):
    """a_p(s) of 1d widget i (`_pack_profiles`)."""
    lo, hi = tf.opacity_start[i], tf.opacity_start[i + 1]
    return min(max(interp(tf.opacity_x[lo:hi], tf.opacity_a[lo:hi], s), 0.0), 1.0)


@njit(nogil=True, cache=True)
def _profile_color(tf, i, s, channel):
    """One channel of c_p(s) of 1d widget i."""
    lo, hi = tf.color_start[i], tf.color_start[i + 1]
    return min(max(interp(tf.color_x[lo:hi], tf.color_rgb[lo:hi, channel], s), 0.0), 1.0)


@njit(nogil=True, cache=True)
def widget_opacity(kind, p, peak, s, g):
    """a_i(s, g) of one widget (the formulas of `model.transfer_function_2d`)."""
    if kind == GAUSSIAN:
        ds = (s - p[0]) / p[2]
        dg = (g - p[1]) / p[3]
        return peak * math.exp(-0.5 * ds * ds - 0.5 * dg * dg)
    if kind == BOX:
        if p[0] <= s <= p[1] and p[2] <= g <= p[3]:
            return peak
        return 0.0
    d = abs(s - p[0])
    h = p[1] * g / p[2]
    if g < 0.0 or g > p[2] or d > h:
        return 0.0
    if h > 0.0:
        return peak * (1.0 - d / h)
    return peak


@njit(nogil=True, cache=True)
def eval_tf2d(tf, s, g):
    """(r, g, b, a) of the 2D TF at value s and gradient magnitude g (colour not premultiplied)."""
    if not (math.isfinite(s) and math.isfinite(g)):
        return 0.0, 0.0, 0.0, 0.0
    types = tf.types
    params = tf.params
    rgb = tf.rgb
    peak = tf.peak
    rect = tf.rect
    s = min(max(s, rect[0]), rect[1])
    g = min(max(g, 0.0), rect[2])
    transmit = 1.0
    weight = 0.0
    r = 0.0
    gr = 0.0
    b = 0.0
    bands = 0  # 1d widgets whose band holds g, and the sum of their colours
    band_r = 0.0
    band_g = 0.0
    band_b = 0.0
    for i in range(types.shape[0]):
        wr, wg, wb = rgb[i, 0], rgb[i, 1], rgb[i, 2]
        if types[i] == PROFILE:
            a = 0.0
            if params[i, 0] <= g <= params[i, 1]:
                a = peak[i] * _profile_opacity(tf, i, s)
                wr *= _profile_color(tf, i, s, 0)
                wg *= _profile_color(tf, i, s, 1)
                wb *= _profile_color(tf, i, s, 2)
                bands += 1
                band_r += wr
                band_g += wg
                band_b += wb
        else:
            a = widget_opacity(types[i], params[i], peak[i], s, g)
        if a > 0.0:
            transmit *= 1.0 - a
            weight += a
            r += a * wr
            gr += a * wg
            b += a * wb
    alpha = min(max(1.0 - transmit, 0.0), 1.0)
    if weight > 0.0:
        r = min(max(r / weight, 0.0), 1.0)
        gr = min(max(gr / weight, 0.0), 1.0)
        b = min(max(b / weight, 0.0), 1.0)
    elif bands > 0:
        r = min(max(band_r / bands, 0.0), 1.0)
        gr = min(max(band_g / bands, 0.0), 1.0)
        b = min(max(band_b / bands, 0.0), 1.0)
    return r, gr, b, alpha


@njit(nogil=True, cache=True)
def _grad_mag(gk, u):
    gx = cubic(gk[0], u)
    gy = cubic(gk[1], u)
    gz = cubic(gk[2], u)
    return math.sqrt(gx * gx + gy * gy + gz * gz)


@njit(nogil=True, cache=True)
def _poly(c, deg, u):
    """c[0] + c[1] u + ... + c[deg] u^deg (Horner)."""
    v = c[deg]
    for i in range(deg - 1, -1, -1):
        v = v * u + c[i]
    return v


@njit(nogil=True, cache=True)
def _poly_root(c, deg, ua, ub, fa, fb):
    """The root in (ua, ub) of a polynomial monotone there with values fa, fb of opposite signs
    (Illinois, then bisection to full precision)."""
    side = 0
    for _ in range(200):
        u = (ua * fb - ub * fa) / (fb - fa)
        if not (ua < u < ub):
            u = 0.5 * (ua + ub)
            if not (ua < u < ub):
                return u
        f = _poly(c, deg, u)
        if f == 0.0:
            return u
        if (f > 0.0) == (fb > 0.0):
            ub = u
            fb = f
            if side == -1:
                fa *= 0.5
            side = -1
        else:
            ua = u
            fa = f
            if side == 1:
                fb *= 0.5
            side = 1
    return 0.5 * (ua + ub)


@njit(nogil=True, cache=True)
def _magnitude_poly(gk, out):
    """Coefficients (degree 6) of |grad s|^2 along the interval, from the three gradient cubics."""
    for i in range(7):
        out[i] = 0.0
    for axis in range(3):
        c = gk[axis]
        for i in range(4):
            for j in range(4):
                out[i + j] += c[i] * c[j]


@njit(nogil=True, cache=True)
def _poly_crossings(poly, length, level, out):
    """Every u in (0, length) where the polynomial (coefficients poly[0..deg], deg = len - 1) crosses
    `level`, ascending: the roots of each derivative split the interval into monotone spans for
    the one before it, from the linear derivative down to the polynomial itself. Fills out (if
    long enough), returns the count."""
    deg = poly.shape[0] - 1
    # row d holds the d-th derivative's coefficients (degree deg - d)
    der = np.zeros((deg + 1, deg + 1))
    for i in range(deg + 1):
        der[0, i] = poly[i]
    der[0, 0] -= level
    for d in range(1, deg + 1):
        for i in range(deg + 1 - d):
            der[d, i] = der[d - 1, i + 1] * (i + 1)
    knots = np.empty(deg + 2)
    roots = np.empty(deg + 2)
    nroots = 0  # roots of the derivative one order up, strictly inside (0, length), ascending
    for d in range(deg - 1, -1, -1):
        c = der[d]
        order = deg - d
        nk = 0
        knots[nk] = 0.0
        nk += 1
        for i in range(nroots):
            knots[nk] = roots[i]
            nk += 1
        knots[nk] = length
        nk += 1
        n = 0
        ua = knots[0]
        fa = _poly(c, order, ua)
        for i in range(1, nk):
            ub = knots[i]
            fb = _poly(c, order, ub)
            if ub > ua and ((fa < 0.0 < fb) or (fb < 0.0 < fa)):
                roots[n] = _poly_root(c, order, ua, ub, fa, fb)
                n += 1
            elif fb == 0.0 and i < nk - 1 and (n == 0 or roots[n - 1] < ub):
                roots[n] = ub  # a root exactly on a knot
                n += 1
            ua = ub
            fa = fb
        nroots = n
    for i in range(nroots):
        if out.shape[0] > i:
            out[i] = roots[i]
    return nroots


@njit(nogil=True, cache=True)
def interval_cuts_2d(c, gk, length, tf, shading, thr2, out):
    """Cut points of one interval (see the module docstring), `length` among them, sorted into out
    when it holds them all; returns their count (`refinement.compute_cuts`)."""
    n = _interval_cuts(c, length, tf.value_cuts, out)
    gcuts = tf.gradient_cuts
    smooth = False  # a Gaussian or a triangle: cut where |grad s| turns, too
    for i in range(tf.types.shape[0]):
        if tf.types[i] == GAUSSIAN or tf.types[i] == TRIANGLE:
            smooth = True
    if gcuts.shape[0] > 0 or shading or smooth:
        h2 = np.empty(7)
        _magnitude_poly(gk, h2)
        for i in range(gcuts.shape[0]):
            e = gcuts[i]
            n += _poly_crossings(h2, length, e * e, out[n:] if n < out.shape[0] else out[:0])
        if shading:
            n += _poly_crossings(h2, length, thr2, out[n:] if n < out.shape[0] else out[:0])
        if smooth:
            dh2 = np.empty(6)
            for i in range(6):
                dh2[i] = h2[i + 1] * (i + 1)
            n += _poly_crossings(dh2, length, 0.0, out[n:] if n < out.shape[0] else out[:0])
        edge = np.empty(7)
        for i in range(tf.types.shape[0]):
            if tf.types[i] == TRIANGLE:
                # the edges |s - s0| = (w / gm) g: roots of (s - s0)^2 - (w / gm)^2 |grad s|^2
                p = tf.params[i]
                k2 = (p[1] / p[2]) ** 2
                for j in range(7):
                    edge[j] = -k2 * h2[j]
                for a in range(4):
                    ca = c[a] - p[0] if a == 0 else c[a]
                    for b in range(4):
                        cb = c[b] - p[0] if b == 0 else c[b]
                        edge[a + b] += ca * cb
                n += _poly_crossings(edge, length, 0.0, out[n:] if n < out.shape[0] else out[:0])
    out.sort()
    return n


@njit(nogil=True, cache=True)
def _subdivision(tf, s0, s1, g0, gm, g1):
    """Sub-pieces a piece needs at level 0 for the widgets its (s, g) span meets (step 2)."""
    rect = tf.rect
    types = tf.types
    params = tf.params
    support = tf.support
    cs0 = min(max(s0, rect[0]), rect[1])
    cs1 = min(max(s1, rect[0]), rect[1])
    cg0 = min(max(g0, 0.0), rect[2])
    cgm = min(max(gm, 0.0), rect[2])
    cg1 = min(max(g1, 0.0), rect[2])
    if not (math.isfinite(cg0) and math.isfinite(cgm) and math.isfinite(cg1)):
        return 1.0  # a gradient next to a NaN voxel: transparent there, nothing to resolve
    ds = abs(cs1 - cs0)
    dg = abs(cgm - cg0) + abs(cg1 - cgm)
    slo = min(cs0, cs1)
    shi = max(cs0, cs1)
    glo = min(cg0, min(cgm, cg1))
    ghi = max(cg0, max(cgm, cg1))
    q = 1.0
    for i in range(types.shape[0]):
        kind = types[i]
        if kind == BOX or kind == PROFILE:
            continue
        if shi < support[i, 0] or slo > support[i, 1] or ghi < support[i, 2] or glo > support[i, 3]:
            continue
        p = params[i]
        if kind == GAUSSIAN:
            fs = p[2]
            fg = p[3]
        else:
            fs = p[1] * max(min(ghi / p[2], 1.0), TRIANGLE_MIN_SCALE)
            fg = p[2]
        q = max(q, max(ds / (FRACTION * fs), dg / (FRACTION * fg)))
    return q


@njit(nogil=True, cache=True)
def _share(parts, k, r, g, b, a):
    parts[k, 0] = r
    parts[k, 1] = g
    parts[k, 2] = b
    parts[k, 3] = a


@njit(nogil=True, cache=True)
def _composite_level_2d(intervals, pieces, level, tf, sp, hx, hy, hz, parts):
    """One level of the composite of a ray's `RayIntervals` (as `ray_integral._composite_level`);
    parts[k] receives interval k's share of (r, g, b, a)."""
    ta, tb, P, G, m = intervals
    piece_starts, piece_ends = pieces
    unit = tf.unit
    shading = sp.on
    mult = 1 << level
    T = 1.0
    cr = 0.0
    cg = 0.0
    cb = 0.0
    samples = 0
    caps = 0
    parts[:m] = 0.0
    for k in range(m):
        length = tb[k] - ta[k]
        if not (length > 0.0):
            continue
        r0, g0, b0, T0 = cr, cg, cb, T
        c = P[k]
        gk = G[k]
        u0 = 0.0
        for e in range(piece_starts[k], piece_starts[k + 1]):
            u1 = piece_ends[e]
            umid = 0.5 * (u0 + u1)
            q = _subdivision(
                tf, cubic(c, u0), cubic(c, u1), _grad_mag(gk, u0), _grad_mag(gk, umid), _grad_mag(gk, u1)
            )
            if shading:
                q = max(q, _normal_turn(gk, u0, umid, u1, sp.gradient_threshold) / SHADING_TURN)
            if q > MAX_SUBDIVISION:
                nsub = MAX_SUBDIVISION
                caps += 1
            else:
                nsub = int(math.ceil(q))
            nsub *= mult
            sub = (u1 - u0) / nsub
            for j in range(nsub):
                um = u0 + (j + 0.5) * sub
                r, g, b, a = eval_tf2d(tf, cubic(c, um), _grad_mag(gk, um))
                samples += 1
                if not (a > 0.0):
                    continue
                od = -math.log1p(-min(a, MAX_OPACITY)) / unit * sub
                alpha = -math.expm1(-od)
                ue = u0 + (j + emission_centre(od)) * sub
                re, ge, be, ae = eval_tf2d(tf, cubic(c, ue), _grad_mag(gk, ue))
                if ae > 0.0:
                    r, g, b = re, ge, be
                    uc = ue
                else:
                    uc = um
                if shading:
                    r, g, b = shade(
                        sp, r, g, b, cubic(gk[0], uc), cubic(gk[1], uc), cubic(gk[2], uc), hx, hy, hz
                    )
                w = T * alpha
                cr += w * r
                cg += w * g
                cb += w * b
                T *= math.exp(-od)
                if T < MIN_TRANSMITTANCE:
                    _share(parts, k, cr - r0, cg - g0, cb - b0, T0 - T)
                    return cr, cg, cb, 1.0 - T, samples, caps
            u0 = u1
        _share(parts, k, cr - r0, cg - g0, cb - b0, T0 - T)
    return cr, cg, cb, 1.0 - T, samples, caps


@njit(nogil=True, cache=True)
def share_change(shares, before, m):
    """The change between two levels' interval shares (r, g, b, a) of the pixel: per channel the sum
    over the intervals of the change of each share, so that changes in different cells cannot
    cancel; the largest over the channels."""
    change = 0.0
    for ch in range(4):
        total = 0.0
        for k in range(m):
            total += abs(shares[k, ch] - before[k, ch])
        change = max(change, total)
    return change
