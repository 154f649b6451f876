"""A ray clipped to an axis-aligned box (the slab test)."""

from __future__ import annotations

from numba import njit


@njit(nogil=True, cache=True)
def clip_box(ox, oy, oz, dx, dy, dz, lo, hi, tmin, tmax):
    """Slab test: the parameter range of the ray inside the closed box [lo, hi], within [tmin, tmax]."""
    t0 = tmin
    t1 = tmax
    o = (ox, oy, oz)
    d = (dx, dy, dz)
    for a in range(3):
        if d[a] != 0.0:
            ta = (lo[a] - o[a]) / d[a]
            tb = (hi[a] - o[a]) / d[a]
            if ta > tb:
                ta, tb = tb, ta
            if ta > t0:
                t0 = ta
            if tb < t1:
                t1 = tb
        elif o[a] < lo[a] or o[a] > hi[a]:
            return 1.0, 0.0
    return t0, t1
