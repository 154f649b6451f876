"""The numba kernel of `raycast` for 2D transfer functions (value x gradient magnitude); `march.c`
draws the same image to float rounding where a C compiler is found (`march_native`).

Why a kernel of its own: a 2D TF needs the gradient at every sample, which the 1D march never
reads, and has no pre-integration; keeping it apart leaves the 1D march's hot loop as it is. The
samples are the 1D march's (the midpoint rule on the same planes, `sample_placement`), so a 2D TF
made from a 1D one draws the same image up to its table's resolution.

The gradient is the reference renderer's: central differences in world units at the grid points
(one-sided at the borders), interpolated trilinearly as a vector, then its length (Real-Time
Volume Graphics, section 5.3.1; Kniss et al. 2002 for the 2D TF). The grid points' gradients are
kept quantised to 16 bits per component (`Gradients2D`), as the slicer keeps them in half floats.
Each segment's colour and extinction come from the table bilinearly, its opacity exactly for its
length: 1 - exp(-tau l). Empty bricks (no opacity at any gradient over their value range) are
left in one jump out of the empty box around them, as in the 1D march.
"""

from __future__ import annotations

import math

from numba import njit, prange

from volren.kernels.clip_planes import clip_to_planes
from volren.kernels.sample_placement import ray_segment, ray_segments
from volren.renderers.raycast.march import (
    FAST,
    TILE,
    _box_exit,
    _brick_shift,
    _first_segment_past,
    _pixel_ray,
    _store,
    _value,
)
from volren.renderers.raycast.march_inputs import FLAT, TRANSPARENT, IndexRay


@njit(nogil=True, cache=True, inline="always", fastmath=FAST)
def _gradient_length(grad, px, py, pz):
    """|trilinear interpolant of the grid points' gradient vectors| at index point (px, py, pz)."""
    nz, ny, nx = grad.values.shape[0], grad.values.shape[1], grad.values.shape[2]
    g = grad.values
    i = max(min(int(px), nx - 2), 0)
    j = max(min(int(py), ny - 2), 0)
    k = max(min(int(pz), nz - 2), 0)
    fx = px - i
    fy = py - j
    fz = pz - k
    total = 0.0
    for c in range(3):
        x00 = float(g[k, j, i, c]) + fx * (float(g[k, j, i + 1, c]) - float(g[k, j, i, c]))
        x10 = float(g[k, j + 1, i, c]) + fx * (float(g[k, j + 1, i + 1, c]) - float(g[k, j + 1, i, c]))
        x01 = float(g[k + 1, j, i, c]) + fx * (float(g[k + 1, j, i + 1, c]) - float(g[k + 1, j, i, c]))
        x11 = float(g[k + 1, j + 1, i, c]) + fx * (
            float(g[k + 1, j + 1, i + 1, c]) - float(g[k + 1, j + 1, i, c])
        )
        y0 = x00 + fy * (x10 - x00)
        y1 = x01 + fy * (x11 - x01)
        v = y0 + fz * (y1 - y0)
        total += v * v
    return math.sqrt(total) * grad.unit


@njit(nogil=True, cache=True, inline="always", fastmath=FAST)
def _segment_rgba(tab, grad, s, px, py, pz, length):
    """Premultiplied (r, g, b, a) of a segment `length` long at value s, index point p (where the
    gradient is read if the table needs it there)."""
    table = tab.table
    ng, nv = table.shape[0], table.shape[1]
    fi = min(max((s - tab.lo) * tab.vscale, 0.0), nv - 1.0)
    i0 = min(int(fi), nv - 2)
    kind = tab.kinds[i0]
    if kind == TRANSPARENT:
        return 0.0, 0.0, 0.0, 0.0
    fj = 0.0 if kind == FLAT else min(max(_gradient_length(grad, px, py, pz) * tab.gscale, 0.0), ng - 1.0)
    j0 = min(int(fj), ng - 2)
    wi = fi - i0
    wj = fj - j0
    tau = _bilinear(table, j0, i0, wj, wi, 3)
    if not tau > 0.0:
        return 0.0, 0.0, 0.0, 0.0
    alpha = -math.expm1(-tau * length)
    r = _bilinear(table, j0, i0, wj, wi, 0)
    g = _bilinear(table, j0, i0, wj, wi, 1)
    b = _bilinear(table, j0, i0, wj, wi, 2)
    return r * alpha, g * alpha, b * alpha, alpha


@njit(nogil=True, cache=True, inline="always", fastmath=FAST)
def _bilinear(table, j0, i0, wj, wi, c):
    a0 = table[j0, i0, c] + wi * (table[j0, i0 + 1, c] - table[j0, i0, c])
    a1 = table[j0 + 1, i0, c] + wi * (table[j0 + 1, i0 + 1, c] - table[j0 + 1, i0, c])
    return a0 + wj * (a1 - a0)


@njit(nogil=True, cache=True, inline="always", fastmath=FAST)
def _ray2d(vol, grad, bricks, shift, view, xx, ny_, phase, tab, term):
    """(r, g, b, a, samples, jumps, skipped, terminated) of pixel column xx's ray at NDC y ny_ (as
    `march._ray`)."""
    empty, B = bricks.distance, bricks.size
    h = tab.step
    nz, ny, nx = vol.shape
    ox, oy, oz, dx, dy, dz, ix, iy, iz, wx, wy, wz, t_in, t_out, miss = _pixel_ray(
        view, xx, ny_, nx - 1.0, ny - 1.0, nz - 1.0
    )
    t_far = view.far_depth / (wx * view.view_dir[0] + wy * view.view_dir[1] + wz * view.view_dir[2])
    t0, t1 = clip_to_planes(ox, oy, oz, dx, dy, dz, view.planes, max(t_in, 0.0), min(t_out, t_far))
    r = 0.0
    g = 0.0
    b = 0.0
    a = 0.0
    taken = 0
    jumps = 0
    skipped = 0
    if miss or not t1 > t0:
        return r, g, b, a, taken, jumps, skipped, 0
    ns, first, last = ray_segments(t1 - t0, h, (phase - t0 / h) % 1.0)
    ray = IndexRay(ox, oy, oz, dx, dy, dz, ix, iy, iz, t0, first, last, ns)
    k = 0
    while k < ns:
        tk, lk = ray_segment(t0, first, last, h, ns, k)
        tm = tk + 0.5 * lk
        px, py, pz = ox + tm * dx, oy + tm * dy, oz + tm * dz
        bi = min(max(int(px), 0), nx - 2)
        bj = min(max(int(py), 0), ny - 2)
        bk = min(max(int(pz), 0), nz - 2)
        if shift >= 0:
            bi, bj, bk = bi >> shift, bj >> shift, bk >> shift
        else:
            bi, bj, bk = bi // B, bj // B, bk // B
        d = empty[bk, bj, bi]
        if d > 0:  # an empty brick, and every brick within d - 1 of it: leave their box at once
            e = d - 1
            te = _box_exit(ray, (bi - e) * B, (bj - e) * B, (bk - e) * B, (bi + 1 + e) * B, (bj + 1 + e) * B,
                           (bk + 1 + e) * B)  # fmt: skip
            kn = max(_first_segment_past(te, t0, first, h, False), k + 1)
            skipped += min(kn, ns) - k
            k = kn
            jumps += 1
            continue
        k += 1
        s = _value(vol, px, py, pz)
        taken += 1
        if not math.isfinite(s):
            continue
        cr, cg, cb, ca = _segment_rgba(tab, grad, s, px, py, pz, lk)
        if ca > 0.0:
            tr = 1.0 - a
            r += tr * cr
            g += tr * cg
            b += tr * cb
            a += tr * ca
            if a >= term:
                break
    return r, g, b, a, taken, jumps, skipped, 1 if k < ns else 0


@njit(nogil=True, cache=True, parallel=True, fastmath=FAST)
def march2d(vol, grad, bricks, view, tab, term, tiles, out, counts):
    """`march.march` with a 2D TF (`Table2D` tab, `Gradients2D` grad)."""
    width, height, phases = view.width, view.height, view.phases
    tiles_x = (width + TILE - 1) // TILE
    shift = _brick_shift(bricks.size)
    for q in prange(tiles.shape[0]):
        tile = tiles[q]
        x_start = (tile % tiles_x) * TILE
        y_start = (tile // tiles_x) * TILE
        taken = 0
        jumps = 0
        skipped = 0
        stopped = 0
        for yy in range(y_start, min(y_start + TILE, height)):
            ny_ = 1.0 - (yy + 0.5) / height * 2.0
            for xx in range(x_start, min(x_start + TILE, width)):
                p = yy * width + xx
                r, g, b, a, n, j, sk, st = _ray2d(
                    vol, grad, bricks, shift, view, xx, ny_, phases[p], tab, term
                )
                taken += n
                jumps += j
                skipped += sk
                stopped += st
                _store(out, p, r, g, b, a)
        counts[tile, 0] = taken
        counts[tile, 1] = jumps
        counts[tile, 2] = skipped
        counts[tile, 3] = stopped


@njit(nogil=True, cache=True, parallel=True, fastmath=FAST)
def march2d_pixels(vol, grad, bricks, view, tab, term, pixels, out, counts):
    """`march.march_pixels` with a 2D TF."""
    width, height, phases = view.width, view.height, view.phases
    shift = _brick_shift(bricks.size)
    for q in prange(pixels.shape[0]):
        p = pixels[q]
        yy = p // width
        ny_ = 1.0 - (yy + 0.5) / height * 2.0
        r, g, b, a, n, j, sk, st = _ray2d(
            vol, grad, bricks, shift, view, p - yy * width, ny_, phases[p], tab, term
        )
        counts[q, 0] = n
        counts[q, 1] = j
        counts[q, 2] = sk
        counts[q, 3] = st
        _store(out, q, r, g, b, a)
