"""An opaque cut face where a ray enters the clip region through a plane (`ClipRegion.cap`).

Why a surface of the TF's colour: a plane through a volume shows only what the TF makes opaque
behind it, so the cut itself does not read as a surface; drawing the cut face with the data's
colour there, lit by the plane's normal, shows its shape and keeps the volume's material on it
(Real-Time Volume Graphics, section 15.4: the clip surface shaded by its own orientation, with
the volume's TF). Where the TF makes the value there transparent, no face is drawn.
"""

from __future__ import annotations

import math

from numba import njit

from volren.kernels.shading import shade
from volren.kernels.tf_eval import color, opacity


@njit(nogil=True, cache=True)
def cut_face(tf, s, nx, ny, nz, sp, dx, dy, dz):
    """(r, g, b, visible) of a cut face at value s on the plane of unit normal n, seen along the
    unit direction d, with the `PackedTF` tf and the `ShadeParams` sp: the TF's colour, lit with
    the plane's normal when shading is on (two-sided, as the volume's samples); not visible where
    s is not finite or the TF's opacity at s is zero."""
    if not math.isfinite(s) or not opacity(tf, s) > 0.0:
        return 0.0, 0.0, 0.0, False
    r, g, b = color(tf, s)
    if sp.on:  # the normal as a gradient above the no-shading threshold
        scale = 1.0 + 4.0 * sp.gradient_threshold
        hx, hy, hz = sp.lx - dx, sp.ly - dy, sp.lz - dz
        norm = math.sqrt(hx * hx + hy * hy + hz * hz)
        if norm > 0.0:
            hx, hy, hz = hx / norm, hy / norm, hz / norm
        r, g, b = shade(sp, r, g, b, nx * scale, ny * scale, nz * scale, hx, hy, hz)
    return r, g, b, True
