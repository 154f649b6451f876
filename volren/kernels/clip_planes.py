"""A ray clipped to the kept side of a set of planes (`volren.model.clip_region`).

Each plane's half-space a x + b y + c z + d >= 0 bounds the ray's parameter from one side: where
the ray heads into it (rate > 0) from below, where it heads out (rate < 0) from above. A ray
parallel to a plane is kept whole or lost whole. The result is the exact entry and exit of the
convex kept region, so a cut surface is flat, not a staircase of cells (Real-Time Volume Graphics,
section 15.1).
"""

from __future__ import annotations

from numba import njit


@njit(nogil=True, cache=True, inline="always")
def clip_entry(ox, oy, oz, dx, dy, dz, planes, t0, t1):
    """(t0, t1, entering): (t0, t1) narrowed to where the ray o + t d lies on the kept side of every
    row (a, b, c, d) of `planes` ((m, 4), in the ray's own coordinates), t1 <= t0 when nothing is
    kept; `entering` the row the ray enters the kept region through (the one that moved t0 last),
    or -1 where t0 stayed (the ray enters where it did: the volume's boundary or the near plane).
    A cut face (`ClipRegion.cap`) lies there."""
    entering = -1
    for p in range(planes.shape[0]):
        at_origin = planes[p, 0] * ox + planes[p, 1] * oy + planes[p, 2] * oz + planes[p, 3]
        rate = planes[p, 0] * dx + planes[p, 1] * dy + planes[p, 2] * dz
        if rate > 0.0:
            if -at_origin / rate > t0:
                t0 = -at_origin / rate
                entering = p
        elif rate < 0.0:
            t1 = min(t1, -at_origin / rate)
        elif at_origin < 0.0:
            return t0, min(t1, t0), -1
    return t0, t1, entering


@njit(nogil=True, cache=True, inline="always")
def clip_to_planes(ox, oy, oz, dx, dy, dz, planes, t0, t1):
    """`clip_entry`'s (t0, t1), for the renderers that draw no cut faces."""
    t0, t1, _ = clip_entry(ox, oy, oz, dx, dy, dz, planes, t0, t1)
    return t0, t1
