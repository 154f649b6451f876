"""The numba kernel of `raycast`: every pixel's ray marched front to back through the grid.

Why a CPU ray caster beside object order: when a cell projects to about a pixel (bonsai's 256^3 at
512^2), object order pays per cell (its footprint, a slab test per pixel) about as much as for the
samples in it; an image-order march pays per sample only, and a ray stops as soon as it is opaque.
Empty space is skipped per brick of cells (`occupancy`): a 3D DDA walks the bricks along the ray,
and from a brick with empty bricks all around it jumps out of the whole empty box at once.

Sample positions are a ray caster's midpoint rule (`volren.kernels.sample_placement`, shared with
objectorder): the ray, clipped to the grid's box and the far plane, is cut into segments of the step
h at t = (phase + j) h from its origin on the near plane (under a parallel projection, planes shared
by all pixels; the first and last segments cut by the box). Post-classified, each segment is
sampled at its middle and its opacity corrected to its length; pre-integrated, each segment is
looked up by the values at its two ends (the back value carried to the next segment), shorter
segments corrected to their length.
A segment whose key point (the middle; pre-integrated, the front, with bricks classified over the
cells a segment can reach from them too) lies in an empty brick adds nothing and is skipped. Non-finite values add
nothing either.
"""

from __future__ import annotations

import math

from numba import njit, prange

from volren.kernels.clip_planes import clip_entry, clip_to_planes
from volren.kernels.sample_placement import ray_segment, ray_segments
from volren.kernels.trilinear import trilinear_value as _value
from volren.model.transfer_function import MAX_OPACITY
from volren.renderers.raycast.march_inputs import COUNTS, TILE, IndexRay

__all__ = ["COUNTS", "FAST", "MAX_OPACITY", "TILE", "march", "march_pixels", "project"]

#: numba's fast-math flags that keep non-finite values visible (they add nothing): fused multiply-add,
#: reciprocals, signed zeros, approximate functions took 13-15 % off a frame on the smooth TFs of
#: ironProt and bonsai (interleaved in one process, same image). Not 'nnan' or 'ninf', and not
#: 'reassoc' either: with it NaN and Inf samples leaked into the image (the kit's NaN check).
FAST = {"contract", "nsz", "arcp", "afn"}
#: Post-classified segments of visible bricks held back before they are composited (`_composite_post`)
MAX_RUN = 64


@njit(nogil=True, cache=True, inline="always", fastmath=FAST)
def _first_segment_past(t, t0, first, h, pre):
    """The first segment whose key point (its front pre-integrated, else its middle) lies at or past
    t; 0 when t is within the first segment."""
    if not t > t0 + first:
        return 0
    return int(math.ceil((t - t0 - first) / h + (1.0 if pre else 0.5) - 1e-9))


@njit(nogil=True, cache=True, inline="always", fastmath=FAST)
def _middles_before(t, t0, first, last, h, ns):
    """How many of a ray's segments have their middle (a post-classified segment's key point) before t."""
    if ns == 0 or not t > t0 + 0.5 * first:
        return 0
    c = max(int(math.ceil((t - t0 - first) / h + 0.5)), 1)
    if c >= ns:
        return ns
    if c == ns - 1 and ns >= 2 and t0 + first + (ns - 2) * h + 0.5 * last < t:
        return ns
    return c


@njit(nogil=True, cache=True, inline="always", fastmath=FAST)
def _composite_post(vol, classes, ray, ka, kb, r, g, b, a, term):
    """(r, g, b, a, segments sampled) after compositing the post-classified segments [ka, kb) of
    the `IndexRay` ray front to back onto it, stopping once a reaches `term`. One counted loop over a run of
    visible bricks: the per-brick loop's exit test at every sample and its mispredicted exit at
    every brick go (7-12 % of a frame on bonsai and marschner_lobb, interleaved in one process)."""
    post, lo_, scale_, h = classes.post, classes.lo, classes.scale, classes.step
    ox, oy, oz, dx, dy, dz = ray.ox, ray.oy, ray.oz, ray.dx, ray.dy, ray.dz
    t0, first, last, ns = ray.t0, ray.first, ray.last, ray.n_segments
    n_ = post.shape[0]
    base = t0 + first - 0.5 * h
    sampled = kb - ka
    for kk in range(ka, kb):
        if kk == 0 or kk == ns - 1:
            tk, lk = ray_segment(t0, first, last, h, ns, kk)
            tm = tk + 0.5 * lk
        else:
            lk = h
            tm = base + kk * h
        s = _value(vol, ox + tm * dx, oy + tm * dy, oz + tm * dz)
        if not math.isfinite(s):
            continue
        fi = min(max((s - lo_) * scale_, 0.0), n_ - 1.0)
        i0 = min(int(fi), n_ - 2)
        w = fi - i0
        ca = post[i0, 3] + w * (post[i0 + 1, 3] - post[i0, 3])
        if ca <= 0.0:
            continue
        if lk != h:
            ca = -math.expm1(lk / h * math.log1p(-min(ca, MAX_OPACITY)))
        tr = (1.0 - a) * ca
        r += tr * (post[i0, 0] + w * (post[i0 + 1, 0] - post[i0, 0]))
        g += tr * (post[i0, 1] + w * (post[i0 + 1, 1] - post[i0, 1]))
        b += tr * (post[i0, 2] + w * (post[i0 + 1, 2] - post[i0, 2]))
        a += tr
        if a >= term:
            sampled = kk + 1 - ka
            break
    return r, g, b, a, sampled


@njit(nogil=True, cache=True, inline="always", fastmath=FAST)
def _box_exit(ray, lx, ly, lz, hx, hy, hz):
    """Where the `IndexRay` ray (origin o, direction d, 1 / d = i) leaves the index box [l, h]."""
    ox, oy, oz, dx, dy, dz, ix, iy, iz = (
        ray.ox,
        ray.oy,
        ray.oz,
        ray.dx,
        ray.dy,
        ray.dz,
        ray.ix,
        ray.iy,
        ray.iz,
    )
    te = math.inf
    if dx > 0.0:
        te = min(te, (hx - ox) * ix)
    elif dx < 0.0:
        te = min(te, (lx - ox) * ix)
    if dy > 0.0:
        te = min(te, (hy - oy) * iy)
    elif dy < 0.0:
        te = min(te, (ly - oy) * iy)
    if dz > 0.0:
        te = min(te, (hz - oz) * iz)
    elif dz < 0.0:
        te = min(te, (lz - oz) * iz)
    return te


@njit(nogil=True, cache=True, inline="always", fastmath=FAST)
def _classify(s, sb, length, classes):
    """Premultiplied (r, g, b, a) of a segment `length` long (`Classification` classes):
    post-classified at value s, or pre-integrated from s (front) to sb (back); (0, 0, 0, 0) where
    a value is not finite."""
    pre, post, table, h = classes.preintegrated, classes.post, classes.table, classes.step
    if not (math.isfinite(s) and math.isfinite(sb)):
        return 0.0, 0.0, 0.0, 0.0
    if pre:
        n = table.shape[0]
        fi = min(max((s - classes.lo) * classes.scale, 0.0), n - 1.0)
        fj = min(max((sb - classes.lo) * classes.scale, 0.0), n - 1.0)
        i0 = min(int(fi), n - 2)
        j0 = min(int(fj), n - 2)
        wi = fi - i0
        wj = fj - j0
        w00 = (1.0 - wi) * (1.0 - wj)
        w01 = (1.0 - wi) * wj
        w10 = wi * (1.0 - wj)
        w11 = wi * wj
        a = (
            w00 * table[i0, j0, 3]
            + w01 * table[i0, j0 + 1, 3]
            + w10 * table[i0 + 1, j0, 3]
            + w11 * table[i0 + 1, j0 + 1, 3]
        )
        if a <= 0.0:
            return 0.0, 0.0, 0.0, 0.0
        r = (
            w00 * table[i0, j0, 0]
            + w01 * table[i0, j0 + 1, 0]
            + w10 * table[i0 + 1, j0, 0]
            + w11 * table[i0 + 1, j0 + 1, 0]
        )
        g = (
            w00 * table[i0, j0, 1]
            + w01 * table[i0, j0 + 1, 1]
            + w10 * table[i0 + 1, j0, 1]
            + w11 * table[i0 + 1, j0 + 1, 1]
        )
        b = (
            w00 * table[i0, j0, 2]
            + w01 * table[i0, j0 + 1, 2]
            + w10 * table[i0 + 1, j0, 2]
            + w11 * table[i0 + 1, j0 + 1, 2]
        )
        if length != h:  # a shorter segment: opacity to its length, colour in proportion
            a2 = -math.expm1(length / h * math.log1p(-min(a, MAX_OPACITY)))
            f = a2 / a
            return r * f, g * f, b * f, a2
        return r, g, b, a
    n = post.shape[0]
    fi = min(max((s - classes.lo) * classes.scale, 0.0), n - 1.0)
    i0 = min(int(fi), n - 2)
    w = fi - i0
    a = post[i0, 3] + w * (post[i0 + 1, 3] - post[i0, 3])
    if a <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    if length != h:
        a = -math.expm1(length / h * math.log1p(-min(a, MAX_OPACITY)))
    r = post[i0, 0] + w * (post[i0 + 1, 0] - post[i0, 0])
    g = post[i0, 1] + w * (post[i0 + 1, 1] - post[i0, 1])
    b = post[i0, 2] + w * (post[i0 + 1, 2] - post[i0, 2])
    return r * a, g * a, b * a, a


@njit(nogil=True, cache=True, inline="always", fastmath=FAST)
def _cut_face(classes, s):
    """(r, g, b, visible) of an opaque cut face at value s (`ClipRegion.cap`): the TF's colour there
    (`Classification.post`), visible where its opacity is above zero and s is finite."""
    post = classes.post
    n = post.shape[0]
    if not math.isfinite(s):
        return 0.0, 0.0, 0.0, False
    fi = min(max((s - classes.lo) * classes.scale, 0.0), n - 1.0)
    i0 = min(int(fi), n - 2)
    w = fi - i0
    a = post[i0, 3] + w * (post[i0 + 1, 3] - post[i0, 3])
    r = post[i0, 0] + w * (post[i0 + 1, 0] - post[i0, 0])
    g = post[i0, 1] + w * (post[i0 + 1, 1] - post[i0, 1])
    b = post[i0, 2] + w * (post[i0 + 1, 2] - post[i0, 2])
    return r, g, b, a > 0.0


@njit(nogil=True, cache=True, inline="always", fastmath=FAST)
def _pixel_ray(view, xx, ny_, ux, uy, uz):
    """Pixel (xx, row at NDC y ny_)'s ray of the `PixelView` view in grid-index space: origin on the
    near plane, direction in index units per world unit, its inverse, the unit world direction,
    and where it enters and leaves the box [0, u] (miss: parallel to a face and outside it)."""
    inv, width, grid_origin, spacing = view.inverse, view.width, view.grid_origin, view.spacing
    nx_ = (xx + 0.5) / width * 2.0 - 1.0
    wn = inv[3, 0] * nx_ + inv[3, 1] * ny_ - inv[3, 2] + inv[3, 3]
    wf = inv[3, 0] * nx_ + inv[3, 1] * ny_ + inv[3, 2] + inv[3, 3]
    n0 = (inv[0, 0] * nx_ + inv[0, 1] * ny_ - inv[0, 2] + inv[0, 3]) / wn
    n1 = (inv[1, 0] * nx_ + inv[1, 1] * ny_ - inv[1, 2] + inv[1, 3]) / wn
    n2 = (inv[2, 0] * nx_ + inv[2, 1] * ny_ - inv[2, 2] + inv[2, 3]) / wn
    wx = (inv[0, 0] * nx_ + inv[0, 1] * ny_ + inv[0, 2] + inv[0, 3]) / wf - n0
    wy = (inv[1, 0] * nx_ + inv[1, 1] * ny_ + inv[1, 2] + inv[1, 3]) / wf - n1
    wz = (inv[2, 0] * nx_ + inv[2, 1] * ny_ + inv[2, 2] + inv[2, 3]) / wf - n2
    norm = math.sqrt(wx * wx + wy * wy + wz * wz)
    wx, wy, wz = wx / norm, wy / norm, wz / norm
    ox = (n0 - grid_origin[0]) / spacing[0]
    oy = (n1 - grid_origin[1]) / spacing[1]
    oz = (n2 - grid_origin[2]) / spacing[2]
    dx, dy, dz = wx / spacing[0], wy / spacing[1], wz / spacing[2]
    ix = 1.0 / dx if dx != 0.0 else math.inf
    iy = 1.0 / dy if dy != 0.0 else math.inf
    iz = 1.0 / dz if dz != 0.0 else math.inf
    t_in = -math.inf
    t_out = math.inf
    miss = False
    for a_ in range(3):
        o_ = ox if a_ == 0 else (oy if a_ == 1 else oz)
        d_ = dx if a_ == 0 else (dy if a_ == 1 else dz)
        i_ = ix if a_ == 0 else (iy if a_ == 1 else iz)
        u_ = ux if a_ == 0 else (uy if a_ == 1 else uz)
        if d_ == 0.0:
            if o_ < 0.0 or o_ > u_:
                miss = True
        else:
            ta = (0.0 - o_) * i_
            tb = (u_ - o_) * i_
            t_in = max(t_in, min(ta, tb))
            t_out = min(t_out, max(ta, tb))
    return ox, oy, oz, dx, dy, dz, ix, iy, iz, wx, wy, wz, t_in, t_out, miss


@njit(nogil=True, cache=True, inline="always", fastmath=FAST)
def _ray(vol, bricks, shift, view, xx, ny_, phase, classes, term):
    """(r, g, b, a, samples, jumps, skipped, terminated): pixel column xx's ray at NDC y ny_ of the
    `PixelView` view marched front to back through the `EmptyBricks` bricks (premultiplied, not yet
    clamped), with the `Classification` classes, stopping once a reaches `term`; `shift`: log2 of
    the brick size, or -1. `skipped`: the segments before the ray stopped that lay in empty bricks;
    `terminated`: 1 where the ray became opaque before its last segment."""
    empty, B = bricks.distance, bricks.size
    view_dir, t_far_eye = view.view_dir, view.far_depth
    pre, h = classes.preintegrated, classes.step
    nz, ny, nx = vol.shape
    nbz, nby, nbx = empty.shape
    ux, uy, uz = nx - 1.0, ny - 1.0, nz - 1.0
    taken = 0
    jumps = 0
    ox, oy, oz, dx, dy, dz, ix, iy, iz, wx, wy, wz, t_in, t_out, miss = _pixel_ray(view, xx, ny_, ux, uy, uz)
    r = 0.0
    g = 0.0
    b = 0.0
    a = 0.0
    t_far = t_far_eye / (wx * view_dir[0] + wy * view_dir[1] + wz * view_dir[2])
    t0, t1, entering = clip_entry(ox, oy, oz, dx, dy, dz, view.planes, max(t_in, 0.0), min(t_out, t_far))
    if classes.cap and entering >= 0 and not miss and t1 > t0:  # the ray meets a cut face first
        cr, cg, cb, visible = _cut_face(classes, _value(vol, ox + t0 * dx, oy + t0 * dy, oz + t0 * dz))
        if visible:
            return cr, cg, cb, 1.0, 1, 0, 0, 0
    ns = 0
    first = 0.0
    last = 0.0
    if not miss and t1 > t0:
        ns, first, last = ray_segments(t1 - t0, h, (phase - t0 / h) % 1.0)
    ray = IndexRay(ox, oy, oz, dx, dy, dz, ix, iy, iz, t0, first, last, ns)
    k = 0  # the next segment
    sb = 0.0  # pre-integrated: the value at segment k's front, when `have_front`
    have_front = False
    ra = 0  # post-classified: segments [ra, rb) lie in a run of visible bricks, not yet composited
    rb = 0
    stop = ns  # the segment after the one that made the ray opaque
    visited = 0  # pre-integrated: segments looked up (`taken` counts their end values)
    while k < ns:
        # (re)start the brick walk at segment k's key point
        tk, lk = ray_segment(t0, first, last, h, ns, k)
        tkey = tk if pre else tk + 0.5 * lk
        bi = min(max(int(ox + tkey * dx), 0), nx - 2)
        bj = min(max(int(oy + tkey * dy), 0), ny - 2)
        bk = min(max(int(oz + tkey * dz), 0), nz - 2)
        if shift >= 0:
            bi, bj, bk = bi >> shift, bj >> shift, bk >> shift
        else:
            bi, bj, bk = bi // B, bj // B, bk // B
        d = empty[bk, bj, bi]
        sx = 1 if dx > 0.0 else -1
        sy = 1 if dy > 0.0 else -1
        sz = 1 if dz > 0.0 else -1
        tnx = ((bi + (1 if dx > 0.0 else 0)) * B - ox) * ix if dx != 0.0 else math.inf
        tny = ((bj + (1 if dy > 0.0 else 0)) * B - oy) * iy if dy != 0.0 else math.inf
        tnz = ((bk + (1 if dz > 0.0 else 0)) * B - oz) * iz if dz != 0.0 else math.inf
        ddx = B * abs(ix)
        ddy = B * abs(iy)
        ddz = B * abs(iz)
        restart = False
        while True:
            if rb > ra and (d != 0 or rb - ra >= MAX_RUN):
                # the run ends at an empty brick, or is long (an opaque ray stops within
                # it: walk no further first): composite it
                r, g, b, a, n_run = _composite_post(vol, classes, ray, ra, rb, r, g, b, a, term)
                taken += n_run
                if a >= term:
                    stop = ra + n_run
                    k = ns
                    break
                ra = rb
            if d > 1:  # empty bricks all around: leave their box in one jump if that skips
                e = d - 1
                tb_ = _box_exit(ray, (bi - e) * B, (bj - e) * B, (bk - e) * B, (bi + 1 + e) * B, (bj + 1 + e) * B,
                                (bk + 1 + e) * B)  # fmt: skip
                kn = _first_segment_past(tb_, t0, first, h, pre)
                if kn > k:
                    k = kn
                    have_front = False
                    jumps += 1
                    restart = True
                    break
            te = min(tnx, tny, tnz)
            if d == 0 and not pre:  # its segments join the run, composited when it ends
                kn = _middles_before(te, t0, first, last, h, ns)
                if kn > k:
                    if rb != k:
                        ra = k
                    rb = kn
                    k = kn
            elif d == 0:
                while k < ns:
                    tk, lk = ray_segment(t0, first, last, h, ns, k)
                    if (tk if pre else tk + 0.5 * lk) >= te:
                        break
                    if pre:
                        if not have_front:
                            s = _value(vol, ox + tk * dx, oy + tk * dy, oz + tk * dz)
                            taken += 1
                        else:
                            s = sb
                        tb2 = tk + lk
                        sb = _value(vol, ox + tb2 * dx, oy + tb2 * dy, oz + tb2 * dz)
                        have_front = True
                    else:
                        tm = tk + 0.5 * lk
                        s = _value(vol, ox + tm * dx, oy + tm * dy, oz + tm * dz)
                        sb = s
                    taken += 1
                    k += 1
                    visited += 1
                    cr, cg, cb, ca = _classify(s, sb, lk, classes)
                    if ca > 0.0:
                        tr = 1.0 - a
                        r += tr * cr
                        g += tr * cg
                        b += tr * cb
                        a += tr * ca
                        if a >= term:
                            stop = k
                            k = ns
                            break
            else:  # an empty brick: its segments add nothing
                kn = _first_segment_past(te, t0, first, h, pre)
                if kn > k:
                    k = kn
                    have_front = False
            if k >= ns:
                break
            if tnx <= tny and tnx <= tnz:
                bi += sx
                tnx += ddx
                if bi < 0 or bi >= nbx:
                    break
            elif tny <= tnz:
                bj += sy
                tny += ddy
                if bj < 0 or bj >= nby:
                    break
            else:
                bk += sz
                tnz += ddz
                if bk < 0 or bk >= nbz:
                    break
            d = empty[bk, bj, bi]
        if not restart:
            break
    if rb > ra and a < term:
        r, g, b, a, n_run = _composite_post(vol, classes, ray, ra, rb, r, g, b, a, term)
        taken += n_run
        if a >= term:
            stop = ra + n_run
    skipped = stop - (visited if pre else taken)
    return r, g, b, a, taken, jumps, skipped, 1 if stop < ns else 0


@njit(nogil=True, cache=True, inline="always", fastmath=FAST)
def _brick_shift(brick):
    """log2 of the brick size where it is a power of two (a shift instead of a division), else -1."""
    shift = -1
    for q_ in range(7):
        if (1 << q_) == brick:
            shift = q_
    return shift


@njit(nogil=True, cache=True, inline="always", fastmath=FAST)
def _store(out, p, r, g, b, a):
    """A pixel's premultiplied colour, clamped to [0, 1] and rgb to at most alpha (rounding can
    leave a channel just above it; interpolation between such pixels keeps the bound)."""
    a = min(max(a, 0.0), 1.0)
    out[p, 0] = min(max(r, 0.0), a)
    out[p, 1] = min(max(g, 0.0), a)
    out[p, 2] = min(max(b, 0.0), a)
    out[p, 3] = a


@njit(nogil=True, cache=True, parallel=True, fastmath=FAST)
def march(vol, bricks, view, classes, term, tiles, out, counts):
    """Render the tiles `tiles` (indices into the image's TILE x TILE tiles, row-major) of the
    `PixelView` view into `out` ((height * width, 4), premultiplied RGBA, row 0 at the top);
    `counts[tile]` = (samples, jumps, segments skipped, rays terminated early) (`COUNTS`). `bricks`: `EmptyBricks`; `classes`: `Classification`; a
    ray stops once its opacity reaches `term`. (`view.inverse` unprojects pixel centres at NDC depth
    -1 and 1, as `Camera.pixel_rays` does.)"""
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
                r, g, b, a, n, j, sk, st = _ray(vol, bricks, shift, view, xx, ny_, phases[p], classes, term)
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
def march_pixels(vol, bricks, view, classes, term, pixels, out, counts):
    """As `march`, for the listed pixels (row-major indices) only: out[q] and counts[q] are pixel
    pixels[q]'s colour and counts. Adaptive image refinement asks for scattered pixels."""
    width, height, phases = view.width, view.height, view.phases
    shift = _brick_shift(bricks.size)
    for q in prange(pixels.shape[0]):
        p = pixels[q]
        yy = p // width
        ny_ = 1.0 - (yy + 0.5) / height * 2.0
        r, g, b, a, n, j, sk, st = _ray(
            vol, bricks, shift, view, p - yy * width, ny_, phases[p], classes, term
        )
        counts[q, 0] = n
        counts[q, 1] = j
        counts[q, 2] = sk
        counts[q, 3] = st
        _store(out, q, r, g, b, a)


MAXIMUM, MINIMUM, AVERAGE = 1, 2, 3


@njit(nogil=True, cache=True, parallel=True, fastmath=FAST)
def project(vol, view, h, mode, acc):
    """Maximum, minimum or average of the values along every pixel's ray of the `PixelView` view
    at step h into acc[p] = (value,
    weight; weight 0: no finite value met). The same midpoint samples as `march` (the average is
    their length-weighted mean); maximum and minimum also read every point where the ray crosses a
    grid plane and its ends, where a trilinear field's extremes along the ray lie on grid lines."""
    width, height, view_dir, t_far_eye, phases = (
        view.width,
        view.height,
        view.view_dir,
        view.far_depth,
        view.phases,
    )
    nz, ny, nx = vol.shape
    ux, uy, uz = nx - 1.0, ny - 1.0, nz - 1.0
    for yy in prange(height):
        ny_ = 1.0 - (yy + 0.5) / height * 2.0
        for xx in range(width):
            p = yy * width + xx
            ox, oy, oz, dx, dy, dz, ix, iy, iz, wx, wy, wz, t_in, t_out, miss = _pixel_ray(
                view, xx, ny_, ux, uy, uz
            )
            t_far = t_far_eye / (wx * view_dir[0] + wy * view_dir[1] + wz * view_dir[2])
            t0, t1 = clip_to_planes(ox, oy, oz, dx, dy, dz, view.planes, max(t_in, 0.0), min(t_out, t_far))
            value = -math.inf if mode == MAXIMUM else (math.inf if mode == MINIMUM else 0.0)
            weight = 0.0
            if not miss and t1 > t0:
                ns, first, last = ray_segments(t1 - t0, h, (phases[p] - t0 / h) % 1.0)
                for k in range(ns):
                    tk, lk = ray_segment(t0, first, last, h, ns, k)
                    tm = tk + 0.5 * lk
                    s = _value(vol, ox + tm * dx, oy + tm * dy, oz + tm * dz)
                    if not math.isfinite(s):
                        continue
                    if mode == AVERAGE:
                        value += s * lk
                        weight += lk
                    else:
                        value = max(value, s) if mode == MAXIMUM else min(value, s)
                        weight = 1.0
                if mode != AVERAGE:
                    for axis in range(4):  # the grid planes crossed along x, y, z, and the two ends
                        o_ = ox if axis == 0 else (oy if axis == 1 else oz)
                        d_ = dx if axis == 0 else (dy if axis == 1 else dz)
                        if axis < 3 and d_ == 0.0:
                            continue
                        if axis < 3:
                            a_ = o_ + t0 * d_
                            b_ = o_ + t1 * d_
                            m0 = int(math.ceil(min(a_, b_)))
                            m1 = int(math.floor(max(a_, b_)))
                        else:
                            m0 = 0
                            m1 = 1
                        for m in range(m0, m1 + 1):
                            t = ((m - o_) / d_) if axis < 3 else (t0 if m == 0 else t1)
                            t = min(max(t, t0), t1)
                            s = _value(vol, ox + t * dx, oy + t * dy, oz + t * dz)
                            if math.isfinite(s):
                                value = max(value, s) if mode == MAXIMUM else min(value, s)
                                weight = 1.0
            acc[p, 0] = value
            acc[p, 1] = weight
