"""The per-ray integrator of 1D TFs, shared by the uniform and tetrahedral paths.

Why: both volume kinds reduce a pixel ray to the same thing, a front-to-back list of intervals
[ta, tb] on which the reconstructed scalar is a smooth polynomial of the ray parameter: a cubic
inside each trilinear grid cell, a linear function inside each tetrahedron. Gaps between intervals
(empty space, cells with a non-finite corner, the outside of a non-convex mesh) contribute
nothing. Interval k holds s(ta[k] + u) = P[k,0] + P[k,1] u + P[k,2] u^2 + P[k,3] u^3 for u in
[0, tb - ta] and, when shading, gradient component c as the cubic G[k, c, :] in the same u.

Composite (emission-absorption, premultiplied RGBA over black, front to back):
1. Exact cuts. Each interval is cut where s has a critical point, where s crosses a TF breakpoint
   or the value at which the opacity reaches the clamp 1 - 1e-6 (roots to full precision on the
   monotone spans), and, when shading, where |grad s| crosses the no-shading threshold (the
   colour jumps there; located between SWITCH_CHECKS + 1 checks per interval). Cell and
   tetrahedron faces are interval ends already. Between two cuts s is monotone and smooth and
   the TF is linear in s, so the integrand has no kink or jump inside any piece, even across TF
   kinks and steps.
2. The level-0 partition. Interval k is split into n0 = max(1, ceil(len / h0)) equal pieces
   (h0 = step * characteristic length), intersected with the cuts (`refinement.level0_pieces`,
   shared with `tf2d`). A piece whose end values
   both have opacity 0 is skipped (the opacity is linear on it). Otherwise it is subdivided into
   n_sub equal sub-pieces so that s changes by at most FRACTION of the width of the TF
   breakpoint interval it lies in (narrow TF features are resolved) and, when shading, the
   normal turns by at most SHADING_TURN per sub-piece (it turns fast where grad s is small);
   n_sub <= MAX_SUBDIVISION, hits counted.
3. Level L splits every level-0 sub-piece into 2^L equal parts. Each level is the exact bisection
   of the one before, so the levels form a clean h^2 sequence and the change between two levels
   is a faithful error estimate (about 3x the error of the finer one).
4. Each (sub-)piece of length l is integrated in exact-exponential form:
   alpha = 1 - exp(-tau_mean l),  C += T alpha c(s(u_e))  (c shaded when shading is on),
   T *= exp(-tau_mean l); the ray's alpha is 1 - T.
   - tau_mean is the exact mean of tau = -ln(1 - min(a, 1 - 1e-6)) / d_u over the piece's value
     span (`volren.kernels.tf_eval.mean_extinction`; the clamped opacity is linear there): exact for linear s
     (tetrahedra), second order for cubic s, and without the first-order error that the
     logarithmic spike of tau near opacity 1 gives tau(s(midpoint)).
   - u_e = l (1/x - 1/(e^x - 1)), x = tau_mean l, is where a homogeneous piece emits on average
     (the midpoint when thin, nearer the front when optically thick), so a colour varying
     linearly across a homogeneous piece is integrated exactly; the midpoint would leave a
     first-order error at every opaque surface.
   Both are exact for homogeneous pieces, like the plain midpoint rule in this form.
5. A ray stops early only when T < 1e-9 (negligible against any sensible tolerance).
6. Levels are computed until two successive ones agree (`refinement.integrate_ray`, which sorts
   the cuts of step 1 and runs the levels of this module's quadrature and of `tf2d`'s).

Maximum / minimum / average need no refinement: the extremes of a cubic on an interval (its ends
and the roots of its derivative) and its integral have closed forms, so the max, min and
length-weighted mean of s over the data along the ray are exact. The value v is mapped to
RGBA = (c(v) a(v), a(v)) with the TF opacity (no length correction); a ray that meets no finite
data gives 0.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from volren.kernels.shading import shade
from volren.kernels.tf_eval import (
    color,
    interval_width,
    mean_extinction,
    opacity,
    opacity_line,
)
from volren.model.preintegration.segment_math import emission_centre

COMPOSITE, MAXIMUM, MINIMUM, AVERAGE = 0, 1, 2, 3

#: In the level-0 partition a piece is subdivided so that s changes by at most this fraction of
#: the width of the TF breakpoint interval it lies in (finer levels bisect these sub-pieces).
FRACTION = 0.25
#: Most sub-pieces per piece; hitting it is counted (`subdivision_cap_hits`).
MAX_SUBDIVISION = 256
#: With shading, a piece is subdivided so that the normal turns by at most this (radians) per
#: sub-piece at level 0 (the normalised gradient turns fast near zeros of the gradient).
SHADING_TURN = 0.25
#: With shading, |grad s| is checked at this many + 1 points per interval for crossings of the
#: no-shading threshold (the shaded colour jumps there, so the crossings become cuts).
SWITCH_CHECKS = 8
#: Transmittance below which a ray stops.
MIN_TRANSMITTANCE = 1e-9


@njit(nogil=True, cache=True)
def cubic(c, u):
    """c[0] + c[1] u + c[2] u^2 + c[3] u^3 (Horner)."""
    return ((c[3] * u + c[2]) * u + c[1]) * u + c[0]


@njit(nogil=True, cache=True)
def critical_points(c, length):
    """Roots of the cubic's derivative strictly inside (0, length), ascending; NaN where none."""
    a = 3.0 * c[3]
    b = 2.0 * c[2]
    k = c[1]
    r1 = math.nan
    r2 = math.nan
    if a == 0.0:
        if b != 0.0:
            r1 = -k / b
    else:
        disc = b * b - 4.0 * a * k
        if disc > 0.0:
            q = -0.5 * (b + math.copysign(math.sqrt(disc), b))
            r1 = q / a
            r2 = k / q
    if not (0.0 < r1 < length):
        r1 = math.nan
    if not (0.0 < r2 < length):
        r2 = math.nan
    if r1 != r1:
        r1, r2 = r2, math.nan
    elif r2 == r2 and r2 < r1:
        r1, r2 = r2, r1
    return r1, r2


@njit(nogil=True, cache=True)
def _angle(ax, ay, az, bx, by, bz, thr):
    """Angle between two gradients; 0 unless both are shaded (above the threshold)."""
    na = math.sqrt(ax * ax + ay * ay + az * az)
    nb = math.sqrt(bx * bx + by * by + bz * bz)
    if not (na > thr and nb > thr):
        return 0.0
    cx = ay * bz - az * by
    cy = az * bx - ax * bz
    cz = ax * by - ay * bx
    return math.atan2(math.sqrt(cx * cx + cy * cy + cz * cz), ax * bx + ay * by + az * bz)


@njit(nogil=True, cache=True)
def _normal_turn(gk, u0, um, u1, thr):
    """Angle (radians) the gradient direction turns through from u0 over um to u1."""
    x0, y0, z0 = cubic(gk[0], u0), cubic(gk[1], u0), cubic(gk[2], u0)
    xm, ym, zm = cubic(gk[0], um), cubic(gk[1], um), cubic(gk[2], um)
    x1, y1, z1 = cubic(gk[0], u1), cubic(gk[1], u1), cubic(gk[2], u1)
    return _angle(x0, y0, z0, xm, ym, zm, thr) + _angle(xm, ym, zm, x1, y1, z1, thr)


@njit(nogil=True, cache=True)
def _root(c, v, ua, ub, ga, gb):
    """u in (ua, ub) with cubic(c, u) == v, given g = cubic - v of opposite signs ga, gb (Illinois)."""
    if c[2] == 0.0 and c[3] == 0.0 and c[1] != 0.0:
        u = (v - c[0]) / c[1]
        return min(max(u, ua), ub)
    side = 0
    for _ in range(200):
        u = (ua * gb - ub * ga) / (gb - ga)
        if not (ua < u < ub):
            u = 0.5 * (ua + ub)
            if not (ua < u < ub):
                return u
        g = cubic(c, u) - v
        if g == 0.0:
            return u
        if (g > 0.0) == (gb > 0.0):
            ub = u
            gb = g
            if side == -1:
                ga *= 0.5
            side = -1
        else:
            ua = u
            ga = g
            if side == 1:
                gb *= 0.5
            side = 1
    return 0.5 * (ua + ub)


@njit(nogil=True, cache=True)
def _cuts_in_span(c, bp, ua, ub, fa, fb, out, n):
    """Append the breakpoint crossings of the monotone span [ua, ub] to out[n:], in order of u."""
    lo = min(fa, fb)
    hi = max(fa, fb)
    i0 = np.searchsorted(bp, lo, side="right")  # first breakpoint > lo
    i1 = np.searchsorted(bp, hi, side="left")  # one past the last breakpoint < hi
    if fa < fb:
        for i in range(i0, i1):
            if out.shape[0] > n:
                out[n] = _root(c, bp[i], ua, ub, fa - bp[i], fb - bp[i])
            n += 1
    else:
        for i in range(i1 - 1, i0 - 1, -1):
            if out.shape[0] > n:
                out[n] = _root(c, bp[i], ua, ub, fa - bp[i], fb - bp[i])
            n += 1
    if out.shape[0] > n:
        out[n] = ub
    return n + 1


@njit(nogil=True, cache=True)
def _interval_cuts(c, length, bp, out):
    """Fill out with the sorted cut points of one interval (critical points, breakpoint
    crossings, and `length` last); returns their number (out may be too short: count only)."""
    r1, r2 = critical_points(c, length)
    n = 0
    ua = 0.0
    fa = c[0]
    if r1 == r1:
        fr = cubic(c, r1)
        n = _cuts_in_span(c, bp, ua, r1, fa, fr, out, n)
        ua = r1
        fa = fr
    if r2 == r2:
        fr = cubic(c, r2)
        n = _cuts_in_span(c, bp, ua, r2, fa, fr, out, n)
        ua = r2
        fa = fr
    return _cuts_in_span(c, bp, ua, length, fa, cubic(c, length), out, n)


@njit(nogil=True, cache=True)
def _gap2(gk, u, thr2):
    """|grad s|^2 - thr^2 at u: positive where the sample is shaded."""
    gx = cubic(gk[0], u)
    gy = cubic(gk[1], u)
    gz = cubic(gk[2], u)
    return gx * gx + gy * gy + gz * gz - thr2


@njit(nogil=True, cache=True)
def _shading_switches(gk, length, thr2, out):
    """Points where |grad s| crosses the no-shading threshold, located between SWITCH_CHECKS + 1
    equally spaced checks (bisection to full precision); fills out (if long enough), returns the
    count."""
    n = 0
    ua = 0.0
    ha = _gap2(gk, ua, thr2)
    for i in range(1, SWITCH_CHECKS + 1):
        ub = length * i / SWITCH_CHECKS
        hb = _gap2(gk, ub, thr2)
        if (ha > 0.0) != (hb > 0.0):
            if out.shape[0] > n:
                lo = ua
                hi = ub
                for _ in range(200):
                    mid = 0.5 * (lo + hi)
                    if not (lo < mid < hi):
                        break
                    if (_gap2(gk, mid, thr2) > 0.0) == (ha > 0.0):
                        lo = mid
                    else:
                        hi = mid
                out[n] = hi
            n += 1
        ua = ub
        ha = hb
    return n


@njit(nogil=True, cache=True)
def interval_cuts_1d(c, G, k, length, tf_cuts, shading, thr2, out):
    """The cut points of interval k (cubic c; gradient cubics G[k] when shading), sorted, into out
    when it holds them all; returns their count (`refinement.compute_cuts`)."""
    n = _interval_cuts(c, length, tf_cuts, out)
    if shading:
        switches = _shading_switches(G[k], length, thr2, out[n:] if n < out.shape[0] else out[:0])
        if switches > 0:
            out.sort()
        n += switches
    return n


@njit(nogil=True, cache=True)
def next_boundary(u0, length, cuts, ci, cend, p, piece, n):
    """The end of the sub-interval that starts at u0: the next of the n equal pieces' ends
    (p * piece) or the next cut, whichever comes first; returns (u1, ci, p) advanced past it.
    u1 <= u0 means "no progress yet, call again" (a piece end at or before u0 was passed)."""
    while ci < cend and cuts[ci] <= u0:
        ci += 1
    ucut = cuts[ci] if ci < cend else length
    upiece = p * piece if p < n else length
    if upiece <= u0:
        return u0, ci, p + 1
    if ucut < upiece:
        return ucut, ci + 1, p
    if ucut == upiece:
        ci += 1
    return upiece, ci, p + 1


@njit(nogil=True, cache=True)
def _composite_level(intervals, pieces, level, tf, sp, hx, hy, hz):
    """One level of the composite of a ray's `RayIntervals` (r, g, b, a, samples, cap hits): the
    level-0 pieces (`refinement.level0_pieces`: their ends, CSR by interval) bisected `level` times."""
    piece_starts, piece_ends = pieces
    ta, tb, P, G, m = intervals
    unit = tf.unit
    shading = sp.on
    mult = 1 << level
    T = 1.0
    cr = 0.0
    cg = 0.0
    cb = 0.0
    samples = 0
    caps = 0
    for k in range(m):
        length = tb[k] - ta[k]
        if not (length > 0.0):
            continue
        c = P[k]
        u0 = 0.0
        f0 = c[0]
        for e in range(piece_starts[k], piece_starts[k + 1]):
            u1 = piece_ends[e]
            f1 = cubic(c, u1)
            # the TF is linear on this piece: take its opacity line from the piece's middle, so
            # that the ends (on a cut, up to rounding) get the one-sided limits even at steps
            smid = cubic(c, 0.5 * (u0 + u1))
            ox, oa, slope = opacity_line(tf, smid)
            a0 = min(max(oa + slope * (f0 - ox), 0.0), 1.0)
            a1 = min(max(oa + slope * (f1 - ox), 0.0), 1.0)
            if a0 > 0.0 or a1 > 0.0:
                nsub = 1
                width = interval_width(tf, smid)
                if width < math.inf:
                    q = abs(f1 - f0) / (FRACTION * width)
                    if q > MAX_SUBDIVISION:
                        nsub = MAX_SUBDIVISION
                        caps += 1
                    elif q > 1.0:
                        nsub = int(math.ceil(q))
                if shading:
                    turn = _normal_turn(G[k], u0, 0.5 * (u0 + u1), u1, sp.gradient_threshold)
                    if turn > SHADING_TURN:
                        q = turn / SHADING_TURN
                        if q > MAX_SUBDIVISION:
                            caps += 1
                            nsub = MAX_SUBDIVISION
                        elif q > nsub:
                            nsub = int(math.ceil(q))
                nsub *= mult
                sub = (u1 - u0) / nsub
                sa = a0
                for q in range(nsub):
                    if q == nsub - 1:
                        sb = a1
                    else:
                        sb = min(max(oa + slope * (cubic(c, u0 + (q + 1) * sub) - ox), 0.0), 1.0)
                    aa = sa
                    sa = sb
                    if not (aa > 0.0 or sb > 0.0):
                        continue
                    samples += 1
                    od = mean_extinction(aa, sb, unit) * sub
                    alpha = -math.expm1(-od)
                    um = u0 + (q + emission_centre(od)) * sub
                    s = cubic(c, um)
                    r, g, b = color(tf, s)
                    if shading:
                        gk = G[k]
                        r, g, b = shade(
                            sp, r, g, b, cubic(gk[0], um), cubic(gk[1], um), cubic(gk[2], um), hx, hy, hz
                        )
                    w = T * alpha
                    cr += w * r
                    cg += w * g
                    cb += w * b
                    T *= math.exp(-od)
                    if T < MIN_TRANSMITTANCE:
                        return cr, cg, cb, 1.0 - T, samples, caps
            u0 = u1
            f0 = f1
    return cr, cg, cb, 1.0 - T, samples, caps


@njit(nogil=True, cache=True)
def _project(ta, tb, P, m, mode):
    """Exact max / min / length-weighted mean of s over the intervals; (value, found)."""
    found = False
    best = 0.0
    integral = 0.0
    total = 0.0
    for k in range(m):
        length = tb[k] - ta[k]
        if not (length > 0.0):
            continue
        c = P[k]
        if mode == AVERAGE:
            integral += (((c[3] * length / 4.0 + c[2] / 3.0) * length + c[1] / 2.0) * length + c[0]) * length
            total += length
            found = True
            continue
        r1, r2 = critical_points(c, length)
        v0 = c[0]
        v1 = cubic(c, length)
        if mode == MAXIMUM:
            v = max(v0, v1)
            if r1 == r1:
                v = max(v, cubic(c, r1))
            if r2 == r2:
                v = max(v, cubic(c, r2))
            if not found or v > best:
                best = v
        else:
            v = min(v0, v1)
            if r1 == r1:
                v = min(v, cubic(c, r1))
            if r2 == r2:
                v = min(v, cubic(c, r2))
            if not found or v < best:
                best = v
        found = True
    if mode == AVERAGE and found:
        best = integral / total
    return best, found


@njit(nogil=True, cache=True)
def project_ray(ta, tb, P, m, mode, tf):
    """RGBA of one ray in a maximum, minimum or average mode, as `refinement.integrate_ray` gives it."""
    v, found = _project(ta, tb, P, m, mode)
    if not found or not math.isfinite(v):
        return 0.0, 0.0, 0.0, 0.0, 0, 0, True, 0
    a = opacity(tf, v)
    r, g, b = color(tf, v)
    return r * a, g * a, b * a, a, 1, 0, True, 0


@njit(nogil=True, cache=True)
def store_pixel(out, stats, q, result, m):
    """Write one ray's integrate_ray `result` and its interval count `m` into row q."""
    r, g, b, a, samples, level, converged, caps = result
    out[q, 0] = r
    out[q, 1] = g
    out[q, 2] = b
    out[q, 3] = a
    stats[q, 0] = samples
    stats[q, 1] = level
    stats[q, 2] = 0 if converged else 1
    stats[q, 3] = caps
    stats[q, 4] = m
