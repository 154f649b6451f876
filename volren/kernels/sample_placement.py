"""Where a ray caster's samples lie: the midpoint rule on segments cut at a per-pixel phase.

Why: the ray caster and the object-order renderer sample the same way (the slicer's post-classified
march, second order in the step h), and their images agree only while the cuts agree, so the rule
lives here once.

A ray clipped to [t0, t1] is cut into segments of the step h at the boundaries t = (phase + j) h
counted from its origin on the near plane (under a parallel projection, planes shared by all
pixels); the first segment, `first` long, and the last, `last` long, are cut by the box; each
segment has one sample (post-classified, at its middle) standing for its length. Slivers shorter
than 1e-9 h add no segment. Pixel phases: `midpoint` (0), `interleaved` (0 and 1/2 on a
checkerboard: neighbouring pixels sample half a step apart), `random` (seeded).

The kernels carry no fastmath flags of their own: they are inlined into each caller's IR and take
its flags, so each renderer's arithmetic is the one it had with its own copy.
"""

from __future__ import annotations

import math

from numba import njit

from volren.kernels.pixel_phases import pixel_phases

__all__ = ["SLIVER", "pixel_phases", "ray_segment", "ray_segments", "segment_length"]

#: A segment shorter than this many steps is a sliver: it adds no sample.
SLIVER = 1e-9


@njit(nogil=True, cache=True, inline="always")
def ray_segments(length, h, phase):
    """(count, first, last): the segments of a ray `length` long cut at phase + j steps from its start."""
    if not length > SLIVER * h:
        return 0, 0.0, 0.0
    first = phase * h if phase > 0.0 else h
    if length <= first + SLIVER * h:
        return 1, length, length
    rest = length - first
    full = math.floor(rest / h)
    rem = rest - full * h
    if rem > SLIVER * h:
        return int(full) + 2, first, rem
    return int(full) + 1, first, h


@njit(nogil=True, cache=True, inline="always")
def segment_length(first, last, h, count, k):
    """The length of segment k of a ray: the first and last are cut by the box, the rest are h."""
    if k == 0:
        return first
    return last if k == count - 1 else h


@njit(nogil=True, cache=True, inline="always")
def ray_segment(t0, first, last, h, count, k):
    """(start, length) of segment k of a ray."""
    if k == 0:
        return t0, first
    return t0 + first + (k - 1) * h, segment_length(first, last, h, count, k)
