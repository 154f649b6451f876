"""Reference integration of a mixture of terms along a ray: label volumes and channels alike.

Why one integrator: a label volume (`labelled`) and a multi-channel volume (`channels`) give each
point of a ray several terms, each a 1D TF applied to a scalar with a weight, whose extinctions and
emissions add (Max 1995, section 2; Real-Time Volume Graphics, sections 4.4 and 16.5):

    tau(u) = sum_n w_n(u) k_n tau_n(s_n(u)),   q(u) = sum_n w_n(u) k_n tau_n(s_n(u)) c_n(s_n(u)).

Labels: one term per class of the cell's corners, every term on the cell's one scalar, w_n the
trilinear interpolant of the class's indicator, k_n = 1. Channels: one term per drawn channel, each
on its own scalar, w_n = 1, k_n the channel's weight. Along an interval (one cell) every scalar and
weight is a cubic in the ray parameter u (`uniform.trilinear_cubic`), so the mixture is smooth
between the points where some term's scalar crosses a breakpoint of its TF.

How: the level-0 pieces are the plain path's (`refinement.level0_pieces`: steps of h0 intersected
with every term's cuts, `ray_integral`'s exact roots on the cubic's monotone spans). Level L cuts
every piece into 2^L equal parts; each part of length l is integrated in exact-exponential form at
its midpoint: alpha = 1 - exp(-tau l), colour q / tau, composited front to back (premultiplied,
over black). The midpoint rule is second order on smooth pieces, so the levels converge as h^2 and
`refinement.converged` stops them; a ray stops early when its transmittance drops below 1e-9.

Terms reach the kernels as arrays per interval k: term n < nt[k] has TF T[k, n] (an index into
the `label_classes.PackedClasses` tfs and into scale), scalar cubic S[k, n] and weight cubic
W[k, n] (clamped to [0, 1]).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from volren.renderers.reference.label_classes import class_sample
from volren.renderers.reference.ray_integral import MIN_TRANSMITTANCE, _interval_cuts, cubic
from volren.renderers.reference.refinement import converged, level0_pieces


@njit(nogil=True, cache=True)
def _cuts_of(S, T, nt, k, length, tfs, out):
    """The cut points of interval k (every term's breakpoint crossings and critical points, its
    length), sorted into out when it holds them all; returns their count."""
    n = 0
    for e in range(nt[k]):
        c = T[k, e]
        bp = tfs.cuts[tfs.cut_offsets[c] : tfs.cut_offsets[c + 1]]
        part = out[n:] if n < out.shape[0] else out[:0]
        n += _interval_cuts(S[k, e], length, bp, part)
    if n <= out.shape[0] and nt[k] > 1:
        out[:n].sort()
    return n


@njit(nogil=True, cache=True)
def mixture_cuts(ta, tb, S, T, nt, m, tfs):
    """CSR of the sorted cut points of every interval: (offsets (m + 1), cuts)."""
    offsets = np.zeros(m + 1, np.int64)
    empty = np.empty(0)
    for k in range(m):
        length = tb[k] - ta[k]
        count = 0
        if length > 0.0:
            count = _cuts_of(S, T, nt, k, length, tfs, empty)
        offsets[k + 1] = offsets[k] + count
    cuts = np.empty(offsets[m])
    for k in range(m):
        length = tb[k] - ta[k]
        if length > 0.0:
            _cuts_of(S, T, nt, k, length, tfs, cuts[offsets[k] : offsets[k + 1]])
    return offsets, cuts


@njit(nogil=True, cache=True)
def _mixture_level(ta, tb, S, W, T, nt, m, pieces, level, tfs, scale):
    """One level of the composite: every level-0 piece cut into 2^level equal parts, each
    integrated at its midpoint in exact-exponential form; (r, g, b, a, samples)."""
    starts, ends = pieces
    parts = 1 << level
    transmittance = 1.0
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
                for n in range(nt[k]):
                    w = min(max(cubic(W[k, n], um), 0.0), 1.0)
                    if w == 0.0:
                        continue
                    c = T[k, n]
                    t, r, g, b = class_sample(tfs, c, cubic(S[k, n], um))
                    wt = w * scale[c] * t
                    tau += wt
                    qr += wt * r
                    qg += wt * g
                    qb += wt * b
                samples += 1
                if not (tau > 0.0):
                    continue
                od = tau * sub
                weight = transmittance * -math.expm1(-od) / tau
                cr += weight * qr
                cg += weight * qg
                cb += weight * qb
                transmittance *= math.exp(-od)
                if transmittance < MIN_TRANSMITTANCE:
                    return cr, cg, cb, 1.0 - transmittance, samples
            u0 = u1
    return cr, cg, cb, 1.0 - transmittance, samples


@njit(nogil=True, cache=True)
def integrate_mixture_ray(ta, tb, S, W, T, nt, m, tfs, scale, quad):
    """RGBA of one ray over its m intervals of terms, refined until two levels agree to the
    `Quadrature` quad's tolerance: (r, g, b, a, samples, level, converged, cap hits)."""
    if m == 0:
        return 0.0, 0.0, 0.0, 0.0, 0, 0, True, 0
    _, h0, tol, max_levels = quad
    offsets, cuts = mixture_cuts(ta, tb, S, T, nt, m, tfs)
    pieces = level0_pieces(ta, tb, m, offsets, cuts, h0)
    pr = pg = pb = pa = 0.0
    samples = 0
    last = math.inf
    for level in range(max_levels):
        cr, cg, cb, ca, n = _mixture_level(ta, tb, S, W, T, nt, m, pieces, level, tfs, scale)
        change = max(abs(cr - pr), abs(cg - pg), abs(cb - pb), abs(ca - pa))
        pr, pg, pb, pa = cr, cg, cb, ca
        samples += n
        if level > 0:
            if converged(level, change, last, tol):
                return pr, pg, pb, pa, samples, level, True, 0
            last = change
    return pr, pg, pb, pa, samples, max_levels - 1, False, 0
