"""Front-to-back order of the octree and the screen footprint of a node.

Why: compositing in object order is correct only if every ray meets the cells in its own
front-to-back order. An octree gives that order for all rays at once: a ray crosses each of a
node's three split planes at most once, from the eye's side to the other, so visiting the children
in the order of (child bits XOR the eye's side bits) is a visibility order for every ray. Under a
parallel projection the eye's side is the same for every node (the sign of the direction); under
perspective it is the side of the split plane the eye is on, per node, which keeps the order exact.

The footprint is the pixel rectangle of the node's eight projected corners (`screen_matrix`); a
node that reaches behind the eye's plane covers the whole image (conservative). Under a parallel
projection the same rectangle comes from one corner and the edges' images (`footprint_affine`).
"""

from __future__ import annotations

import math

from numba import njit


@njit(nogil=True, cache=True)
def child_order_mask(level, i, j, k, perspective, eye, direction):
    """Bits (x = 1, y = 2, z = 4) of the child nearest the eye for node (level, i, j, k)."""
    mask = 0
    if perspective:
        half = 1 << (level - 1)
        if eye[0] >= (2 * i + 1) * half:
            mask |= 1
        if eye[1] >= (2 * j + 1) * half:
            mask |= 2
        if eye[2] >= (2 * k + 1) * half:
            mask |= 4
    else:
        if direction[0] < 0.0:
            mask |= 1
        if direction[1] < 0.0:
            mask |= 2
        if direction[2] < 0.0:
            mask |= 4
    return mask


@njit(nogil=True, cache=True)
def footprint(M, x0, y0, z0, x1, y1, z1, width, height):
    """(c0, c1, r0, r1), the inclusive pixel rectangle whose centres the box [x0, x1] x [y0, y1] x
    [z0, z1] (grid-index coordinates) may cover; c0 > c1 or r0 > r1 when it is off screen."""
    umin = math.inf
    umax = -math.inf
    vmin = math.inf
    vmax = -math.inf
    for c in range(8):
        x = x1 if c & 1 else x0
        y = y1 if c & 2 else y0
        z = z1 if c & 4 else z0
        w = M[2, 0] * x + M[2, 1] * y + M[2, 2] * z + M[2, 3]
        if w <= 1e-12:
            return 0, width - 1, 0, height - 1
        u = (M[0, 0] * x + M[0, 1] * y + M[0, 2] * z + M[0, 3]) / w
        v = (M[1, 0] * x + M[1, 1] * y + M[1, 2] * z + M[1, 3]) / w
        umin = min(umin, u)
        umax = max(umax, u)
        vmin = min(vmin, v)
        vmax = max(vmax, v)
    return pixel_rect(umin, umax, vmin, vmax, width, height)


@njit(nogil=True, cache=True)
def footprint_affine(M, x0, y0, z0, x1, y1, z1, width, height):
    """`footprint` under a parallel projection (W = 1): the map is affine, so the rectangle is the
    low corner's image widened by each edge's image on its own side, 6 products instead of 24 and
    no divisions (the traversal computes one per node visited)."""
    u = M[0, 0] * x0 + M[0, 1] * y0 + M[0, 2] * z0 + M[0, 3]
    v = M[1, 0] * x0 + M[1, 1] * y0 + M[1, 2] * z0 + M[1, 3]
    umin = umax = u
    vmin = vmax = v
    for a in range(3):
        e = (x1 - x0) if a == 0 else ((y1 - y0) if a == 1 else (z1 - z0))
        du = M[0, a] * e
        dv = M[1, a] * e
        if du < 0.0:
            umin += du
        else:
            umax += du
        if dv < 0.0:
            vmin += dv
        else:
            vmax += dv
    return pixel_rect(umin, umax, vmin, vmax, width, height)


@njit(nogil=True, cache=True)
def pixel_rect(umin, umax, vmin, vmax, width, height):
    """(c0, c1, r0, r1): the pixels whose centres lie in [umin, umax] x [vmin, vmax] (a hair wider)."""
    eps = 1e-6
    umin = max(umin, -2.0)  # far off screen: keep the integer conversions in range
    vmin = max(vmin, -2.0)
    umax = min(umax, width + 1.0)
    vmax = min(vmax, height + 1.0)
    c0 = max(0, int(math.ceil(umin - eps)))
    c1 = min(width - 1, int(math.floor(umax + eps)))
    r0 = max(0, int(math.ceil(vmin - eps)))
    r1 = min(height - 1, int(math.floor(vmax + eps)))
    return c0, c1, r0, r1
