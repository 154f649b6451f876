"""Exact evaluation of a 1D transfer function inside numba kernels.

Why: the reference renderer defines truth, so it must evaluate the TF exactly as DESIGN.md states
it (piecewise linear colour and opacity between control points, constant beyond the ends) at
every sample: no lookup table, no quantisation.

How: `pack_tf` turns a `TransferFunction1D` into plain float64 arrays (a `PackedTF`, a named tuple
that numba passes around as one argument and reads by field name):

    (cx, crgb, ox, oa, bp, unit, cuts)
    cx (nc,)   colour control x, sorted      crgb (nc, 3) colour at cx
    ox (no,)   opacity control x, sorted     oa (no,)     opacity at ox
    bp (nb,)   sorted distinct x of all control points (the TF is linear between two of them)
    unit       opacity_unit_distance d_u
    cuts       bp plus the values where the opacity crosses the clamp 1 - 1e-6: between two
               cuts colour, opacity and min(opacity, 1 - 1e-6) are all linear in s

`interp` finds the interval with a binary search (``x[k] <= s < x[k+1]``, which never selects a
zero-width interval, so duplicated control points make a step) and interpolates linearly;
`opacity_line` returns the linear piece itself, so that a caller can take one-sided limits.

The extinction is tau(s) = -ln(1 - min(a, 1 - 1e-6)) / d_u (DESIGN.md). `mean_extinction` gives
the exact mean of tau over a span of s on which the clamped opacity runs linearly from aa to ab:
with w = 1 - a, mean(-ln w) = -(phi(wb) - phi(wa)) / (wb - wa), phi(w) = w ln w - w, and a
Taylor series in e = (wb - wa) / (wb + wa) where that difference would cancel. It keeps the
optical depth exact as the opacity approaches 1, where tau has a logarithmic spike that the
midpoint rule resolves only at first order.

For the adaptive integrator, np.searchsorted locates the breakpoints a span of
values crosses (the integrator splits the ray exactly there, so the TF is linear on every piece it
integrates), and `interval_width` gives the width of the breakpoint interval a value lies in (how
narrow the TF feature is, which sets how finely a piece is subdivided).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from volren.model.transfer_function import MAX_OPACITY, TransferFunction1D


class PackedTF(NamedTuple):
    """A 1D TF as the kernels read it (the module docstring's (cx, crgb, ox, oa, bp, unit, cuts))."""

    color_x: NDArray[np.float64]
    color_rgb: NDArray[np.float64]
    opacity_x: NDArray[np.float64]
    opacity_a: NDArray[np.float64]
    breakpoints: NDArray[np.float64]
    unit: float
    cuts: NDArray[np.float64]


def pack_tf(tf: TransferFunction1D) -> PackedTF:
    """The TF as float64 arrays for the kernels (see the module docstring)."""
    color = tf.color_points
    opacity = tf.opacity_points
    cx = np.ascontiguousarray(color[:, 0], dtype=np.float64)
    crgb = np.ascontiguousarray(color[:, 1:4], dtype=np.float64)
    ox = np.ascontiguousarray(opacity[:, 0], dtype=np.float64)
    oa = np.ascontiguousarray(opacity[:, 1], dtype=np.float64)
    bp = np.ascontiguousarray(tf.breakpoints(), dtype=np.float64)
    cuts = np.ascontiguousarray(tf.linear_cuts(), dtype=np.float64)
    return PackedTF(cx, crgb, ox, oa, bp, float(tf.opacity_unit_distance), cuts)


@njit(nogil=True, cache=True)
def find_interval(xs, s):
    """k with xs[k] <= s < xs[k+1]; requires xs[0] <= s < xs[-1]."""
    return np.searchsorted(xs, s, side="right") - 1


@njit(nogil=True, cache=True)
def interp(xs, ys, s):
    """Piecewise-linear ys(xs) at s, constant beyond the ends."""
    n = xs.shape[0]
    if s <= xs[0]:
        return ys[0]
    if s >= xs[n - 1]:
        return ys[n - 1]
    k = find_interval(xs, s)
    w = (s - xs[k]) / (xs[k + 1] - xs[k])
    return ys[k] + (ys[k + 1] - ys[k]) * w


@njit(nogil=True, cache=True)
def opacity(tf, s):
    return interp(tf.opacity_x, tf.opacity_a, s)


@njit(nogil=True, cache=True)
def opacity_line(tf, s):
    """(x0, a0, slope): the linear piece of the opacity that holds s, a(x) = a0 + slope (x - x0)."""
    xs = tf.opacity_x
    ys = tf.opacity_a
    n = xs.shape[0]
    if s <= xs[0]:
        return xs[0], ys[0], 0.0
    if s >= xs[n - 1]:
        return xs[n - 1], ys[n - 1], 0.0
    k = find_interval(xs, s)
    return xs[k], ys[k], (ys[k + 1] - ys[k]) / (xs[k + 1] - xs[k])


@njit(nogil=True, cache=True)
def color(tf, s):
    """(r, g, b) at s, not premultiplied."""
    xs = tf.color_x
    rgb = tf.color_rgb
    n = xs.shape[0]
    if s <= xs[0]:
        return rgb[0, 0], rgb[0, 1], rgb[0, 2]
    if s >= xs[n - 1]:
        return rgb[n - 1, 0], rgb[n - 1, 1], rgb[n - 1, 2]
    k = find_interval(xs, s)
    w = (s - xs[k]) / (xs[k + 1] - xs[k])
    return (
        rgb[k, 0] + (rgb[k + 1, 0] - rgb[k, 0]) * w,
        rgb[k, 1] + (rgb[k + 1, 1] - rgb[k, 1]) * w,
        rgb[k, 2] + (rgb[k + 1, 2] - rgb[k, 2]) * w,
    )


@njit(nogil=True, cache=True)
def mean_extinction(aa, ab, unit):
    """Mean of tau over a span where the opacity is linear from aa to ab (exact)."""
    aa = min(aa, MAX_OPACITY)
    ab = min(ab, MAX_OPACITY)
    wa = 1.0 - aa
    wb = 1.0 - ab
    wm = 0.5 * (wa + wb)
    e = 0.5 * (wb - wa) / wm
    if abs(e) < 1e-2:
        e2 = e * e
        mean = -math.log1p(-0.5 * (aa + ab)) + e2 * (
            1.0 / 6.0 + e2 * (1.0 / 20.0 + e2 * (1.0 / 42.0 + e2 / 72.0))
        )
    else:
        phi_a = wa * math.log1p(-aa) - wa
        phi_b = wb * math.log1p(-ab) - wb
        mean = -(phi_b - phi_a) / (wb - wa)
    return mean / unit


@njit(nogil=True, cache=True)
def interval_width(tf, s):
    """Width of the breakpoint interval holding s (the TF is linear across it); +inf outside."""
    bp = tf.breakpoints
    n = bp.shape[0]
    if not (s > bp[0] and s < bp[n - 1]):
        return math.inf
    k = find_interval(bp, s)
    return bp[k + 1] - bp[k]
