"""The numba kernels: object-order traversal of one band of image rows, cell by cell.

Why one kernel per band: a band's pixels are written by nobody else, so bands run in parallel
(prange) without locks, each with its own occlusion map; each band walks the octree front to back
and visits only the nodes whose footprint meets its rows (the top levels are walked by every
band, a few hundred nodes). Inside a leaf cell its eight corners (and, when shading, their
central-difference gradients) are loaded once and shared by every ray of its footprint, the point
of object order (Mora et al. 2002, section 3). Where cells are small on screen (an octree node one level
above them covers at most `block_pixels` pixels) and none of a node's pixels is finished, its 2 x 2
x 2 cells, at least 4 of them visible, are drawn as one block (`_block`, compositing only): one footprint, one load of their 27 grid points, one
slab test per pixel for all of them, the same samples (bonsai's smooth TF at step 1, 512x512: 1.4-1.5x
faster); elsewhere cell by cell, each cell's footprint against the occlusion map as Mora et al. do.

Per pixel of a cell's footprint: the exact slab test gives the ray's interval [tlo, thi) in the
cell; the pixel's depth indicator (`nextk`, its next sample) is moved past samples of skipped cells
and the samples with t in [tlo, thi) are taken, trilinearly, in order. Consecutive cells of a ray
share the plane crossing they meet at (computed by one formula from the plane's index), so every
sample of a ray falls in exactly one cell: the same samples as a ray caster's.

Compositing (front to back, premultiplied): post-classified, sample k stands for its segment of
length L (h, or the first or last segment's), opacity 1 - (1 - a)^(L / d_u) (from a table made for L = h,
or exactly per sample, `_post_rgba`); pre-integrated, sample k closes the
segment from sample k - 1 (table lookup, length-corrected when it is not h), and the pieces from
the ray's entry point on the box to the first sample and from the last to the exit point too. Maximum / minimum take
the samples and the ray's entry and exit points of each cell; average the length-weighted samples.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from volren.kernels.sample_placement import segment_length
from volren.kernels.shading import blinn_phong_factors, headlight_half_vector
from volren_objectorder.bundles import Band, CellBlock, Occlusion, PixelRay, Rect, Sample, Scratch
from volren_objectorder.mixed_samples import is_mixed, mixed_rgba
from volren_objectorder.occlusion import hom_covered, hom_finish, hom_init, hom_layout
from volren_objectorder.octree import bracket
from volren_objectorder.patterns import ray_end, sample_t
from volren_objectorder.traversal import child_order_mask, footprint, footprint_affine

COMPOSITE, MAXIMUM, MINIMUM, AVERAGE = 0, 1, 2, 3
MAX_OPACITY = 1.0 - 1e-6

# per-band counters
S_NODES, S_CELLS, S_OCCLUDED_CELLS, S_OCCLUDED_NODES, S_SAMPLES, S_SATURATED = range(6)
N_STATS = 6


@njit(nogil=True, cache=True)
def tf_lookup(xs, tab, s):
    """Colour and opacity of the piecewise-linear TF (rows of `tab` at `xs`) at s."""
    a, b, f = bracket(xs, s)
    return (tab[a, 0] + f * (tab[b, 0] - tab[a, 0]), tab[a, 1] + f * (tab[b, 1] - tab[a, 1]),
            tab[a, 2] + f * (tab[b, 2] - tab[a, 2]), tab[a, 3] + f * (tab[b, 3] - tab[a, 3]))  # fmt: skip


@njit(nogil=True, cache=True)
def _point_gradient(grid, x, y, z):
    """Central differences at grid point (x, y, z) of the `Grid` in world units, one-sided at the borders."""
    vol = grid.values
    nz, ny, nx = vol.shape
    if x == 0:
        gx = (vol[z, y, 1] - vol[z, y, 0]) * grid.isx
    elif x == nx - 1:
        gx = (vol[z, y, x] - vol[z, y, x - 1]) * grid.isx
    else:
        gx = (vol[z, y, x + 1] - vol[z, y, x - 1]) * 0.5 * grid.isx
    if y == 0:
        gy = (vol[z, 1, x] - vol[z, 0, x]) * grid.isy
    elif y == ny - 1:
        gy = (vol[z, y, x] - vol[z, y - 1, x]) * grid.isy
    else:
        gy = (vol[z, y + 1, x] - vol[z, y - 1, x]) * 0.5 * grid.isy
    if z == 0:
        gz = (vol[1, y, x] - vol[0, y, x]) * grid.isz
    elif z == nz - 1:
        gz = (vol[z, y, x] - vol[z - 1, y, x]) * grid.isz
    else:
        gz = (vol[z + 1, y, x] - vol[z - 1, y, x]) * 0.5 * grid.isz
    return gx, gy, gz


@njit(nogil=True, cache=True)
def _load_block(grid, x0, y0, z0, sx, sy, sz, shade, cb, gb):
    """The grid points of the block of sx x sy x sz cells from (x0, y0, z0), point (x0 + a, y0 + b,
    z0 + c) at cb[9 c + 3 b + a], and, when shading, their gradients."""
    vol = grid.values
    if sx == 1 and sy == 1 and sz == 1 and not shade:  # one cell, unrolled
        cb[0] = vol[z0, y0, x0]
        cb[1] = vol[z0, y0, x0 + 1]
        cb[3] = vol[z0, y0 + 1, x0]
        cb[4] = vol[z0, y0 + 1, x0 + 1]
        cb[9] = vol[z0 + 1, y0, x0]
        cb[10] = vol[z0 + 1, y0, x0 + 1]
        cb[12] = vol[z0 + 1, y0 + 1, x0]
        cb[13] = vol[z0 + 1, y0 + 1, x0 + 1]
        return
    for c in range(sz + 1):
        for b in range(sy + 1):
            for a in range(sx + 1):
                n = 9 * c + 3 * b + a
                cb[n] = vol[z0 + c, y0 + b, x0 + a]
                if shade:
                    gx, gy, gz = _point_gradient(grid, x0 + a, y0 + b, z0 + c)
                    gb[n, 0] = gx
                    gb[n, 1] = gy
                    gb[n, 2] = gz


@njit(nogil=True, cache=True, inline="always")
def _clamp02(x):
    return 0.0 if x < 0.0 else (2.0 if x > 2.0 else x)


@njit(nogil=True, cache=True, inline="always")
def _sub_cell(blk, fx, fy, fz):
    """The cell of block `blk` = (visible cells' bits, sx, sy, sz) holding block-local (fx, fy, fz) in
    [0, 2]^3: (its bit, x + 2 y + 4 z as in the octree's leaf bytes; the index of its first grid point
    among the block's 27; the point's coordinates in it)."""
    ix = min(int(fx), blk[1] - 1)
    iy = min(int(fy), blk[2] - 1)
    iz = min(int(fz), blk[3] - 1)
    return ix + 2 * iy + 4 * iz, iz * 9 + iy * 3 + ix, fx - ix, fy - iy, fz - iz


@njit(nogil=True, cache=True, inline="always")
def _locate_in(blk, x, y, z):
    """The sample at block-local (x, y, z) in block `blk` = (visible cells' bits, sx, sy, sz, size):
    (whether the TF leaves its cell visible, the index of the cell's first grid point among the
    block's 27, the point's coordinates in the cell). A block of one cell (size 1, always visible)
    pays no test of which cell holds the sample: the branch goes the same way for all of a block's
    samples."""
    if blk[4] == 1:
        return True, 0, _clamp01(x), _clamp01(y), _clamp01(z)
    bit, base, fx, fy, fz = _sub_cell(blk, _clamp02(x), _clamp02(y), _clamp02(z))
    return (blk[0] >> bit) & 1 != 0, base, fx, fy, fz


@njit(nogil=True, cache=True, inline="always")
def _trilinear_at(cb, b, fx, fy, fz):
    """Trilinear value at (fx, fy, fz) in [0, 1]^3 of the block's cell whose first grid point is cb[b]."""
    x00 = cb[b] + fx * (cb[b + 1] - cb[b])
    x10 = cb[b + 3] + fx * (cb[b + 4] - cb[b + 3])
    x01 = cb[b + 9] + fx * (cb[b + 10] - cb[b + 9])
    x11 = cb[b + 12] + fx * (cb[b + 13] - cb[b + 12])
    y0 = x00 + fy * (x10 - x00)
    y1 = x01 + fy * (x11 - x01)
    return y0 + fz * (y1 - y0)


@njit(nogil=True, cache=True, inline="always")
def _trilinear_at_g(gb, comp, b, fx, fy, fz):
    x00 = gb[b, comp] + fx * (gb[b + 1, comp] - gb[b, comp])
    x10 = gb[b + 3, comp] + fx * (gb[b + 4, comp] - gb[b + 3, comp])
    x01 = gb[b + 9, comp] + fx * (gb[b + 10, comp] - gb[b + 9, comp])
    x11 = gb[b + 12, comp] + fx * (gb[b + 13, comp] - gb[b + 12, comp])
    y0 = x00 + fy * (x10 - x00)
    y1 = x01 + fy * (x11 - x01)
    return y0 + fz * (y1 - y0)


@njit(nogil=True, cache=True)
def _clamp01(x):
    return 0.0 if x < 0.0 else (1.0 if x > 1.0 else x)


@njit(nogil=True, cache=True)
def _locate(vol, px, py, pz):
    """The cell holding index point (px, py, pz) and the point's local coordinates in it."""
    nz, ny, nx = vol.shape
    i = min(max(int(math.floor(px)), 0), nx - 2)
    j = min(max(int(math.floor(py)), 0), ny - 2)
    k = min(max(int(math.floor(pz)), 0), nz - 2)
    return i, j, k, _clamp01(px - i), _clamp01(py - j), _clamp01(pz - k)


@njit(nogil=True, cache=True)
def _light(gx, gy, gz, hx, hy, hz, shading):
    """(diffuse factor, specular term) at a sample of gradient (gx, gy, gz), with the frame's `ShadeParams`."""
    return blinn_phong_factors(gx, gy, gz, hx, hy, hz, shading)


@njit(nogil=True, cache=True, inline="always")
def _over(rgba, p, r, g, b, a):
    """Front-to-back over of premultiplied (r, g, b, a) into pixel p."""
    t = 1.0 - rgba[p, 3]
    rgba[p, 0] += t * r
    rgba[p, 1] += t * g
    rgba[p, 2] += t * b
    rgba[p, 3] += t * a


@njit(nogil=True, cache=True, inline="always")
def _bilinear(table, fi, fj, c):
    n = table.shape[0]
    i0 = min(int(fi), n - 2)
    j0 = min(int(fj), n - 2)
    wi = fi - i0
    wj = fj - j0
    return ((1.0 - wi) * ((1.0 - wj) * table[i0, j0, c] + wj * table[i0, j0 + 1, c])
            + wi * ((1.0 - wj) * table[i0 + 1, j0, c] + wj * table[i0 + 1, j0 + 1, c]))  # fmt: skip


@njit(nogil=True, cache=True, inline="always")
def _segment(rgba, p, start, end, length, h, shade, tables):
    """A pre-integrated segment from `Sample` start (front) to end (back), `length` long (the tables'
    for step h); lit by interpolated pre-integrated lighting (Lum et al.) when shading."""
    sf, fd_f, sp_f = start
    sb, fd_b, sp_b = end
    table = tables.table
    front = tables.front
    back = tables.back
    n = table.shape[0] if not shade else front.shape[0]
    fi = min(max((sf - tables.lo) * tables.scale, 0.0), n - 1.0)
    fj = min(max((sb - tables.lo) * tables.scale, 0.0), n - 1.0)
    if shade:
        a = _bilinear(front, fi, fj, 3)
        if a <= 0.0:
            return
        sb_spec = _bilinear(back, fi, fj, 3)
        sf_spec = a - sb_spec
        spec = sf_spec * sp_f + sb_spec * sp_b
        r = _bilinear(front, fi, fj, 0) * fd_f + _bilinear(back, fi, fj, 0) * fd_b + spec
        g = _bilinear(front, fi, fj, 1) * fd_f + _bilinear(back, fi, fj, 1) * fd_b + spec
        b = _bilinear(front, fi, fj, 2) * fd_f + _bilinear(back, fi, fj, 2) * fd_b + spec
    else:
        a = _bilinear(table, fi, fj, 3)
        if a <= 0.0:
            return
        r = _bilinear(table, fi, fj, 0)
        g = _bilinear(table, fi, fj, 1)
        b = _bilinear(table, fi, fj, 2)
    if abs(length - h) > 1e-9 * h:  # opacity and colour correction to this length
        ratio = length / h
        corrected = -math.expm1(ratio * math.log1p(-min(a, MAX_OPACITY)))
        scale = corrected / a
        r, g, b, a = r * scale, g * scale, b * scale, corrected
    _over(rgba, p, min(max(r, 0.0), a), min(max(g, 0.0), a), min(max(b, 0.0), a), a)


@njit(nogil=True, cache=True)
def _fetch(grid, px, py, pz, cb, gb):
    """The trilinear value at index point (px, py, pz); NaN when a corner of its cell is not finite
    (a NaN or an infinity reaches the interpolated value whatever the weights; cb: scratch for the
    cell's grid points, laid out as `_load_block`'s; gb: unused, the gradients' scratch)."""
    i, j, k, fx, fy, fz = _locate(grid.values, px, py, pz)
    _load_block(grid, i, j, k, 1, 1, 1, False, cb, gb)
    return _trilinear_at(cb, 0, fx, fy, fz)


@njit(nogil=True, cache=True)
def _fetch_light(grid, px, py, pz, hx, hy, hz, shading, cb, gb):
    """The lighting (diffuse factor, specular term) at index point (px, py, pz) (cb, gb: scratch)."""
    i, j, k, fx, fy, fz = _locate(grid.values, px, py, pz)
    _load_block(grid, i, j, k, 1, 1, 1, True, cb, gb)
    return _light(_trilinear_at_g(gb, 0, 0, fx, fy, fz), _trilinear_at_g(gb, 1, 0, fx, fy, fz),
                  _trilinear_at_g(gb, 2, 0, fx, fy, fz), hx, hy, hz, shading)  # fmt: skip


@njit(nogil=True, cache=True)
def _edge(ray, te, sample, length, entry, grid, ro, tables, frame, shading, rgba, scratch):
    """The pre-integrated piece between the `PixelRay`'s end point at `te` (its entry or exit on the
    box) and its first or last `Sample`; transparent when the end point's cell has a non-finite corner."""
    if length <= 0.0:
        return
    p = ray.p
    shade = shading.on
    e8 = scratch.e8
    eg8 = scratch.eg8
    px = ro[p, 0] + te * ray.dx
    py = ro[p, 1] + te * ray.dy
    pz = ro[p, 2] + te * ray.dz
    se = _fetch(grid, px, py, pz, e8, eg8)
    if not np.isfinite(se):
        return
    fde = 1.0
    spe = 0.0
    if shade:
        fde, spe = _fetch_light(grid, px, py, pz, ray.hx, ray.hy, ray.hz, shading, e8, eg8)
    if entry:
        _segment(rgba, p, Sample(se, fde, spe), sample, length, frame.h, shade, tables)
    else:
        _segment(rgba, p, sample, Sample(se, fde, spe), length, frame.h, shade, tables)


@njit(nogil=True, cache=True, inline="always")
def _slab(rays, grid, p, dp, x0, y0, z0, sx, sy, sz):
    """[tlo, thi) of pixel p's ray (its direction in row dp of the `Rays`' direction and inverse: p,
    or 0 when every ray shares one) in the block of sx x sy x sz cells from cell (x0, y0, z0) of the
    `Grid`, the exact slab test in index space; thi <= tlo when the ray misses the block. Each plane's
    crossing is (q - o) / d from the plane's index q alone, so two blocks sharing a face agree on it
    and every sample falls in exactly one block."""
    ro = rays.origin
    rd = rays.direction
    ri = rays.inverse
    ncx = grid.ncx
    ncy = grid.ncy
    ncz = grid.ncz
    tlo = -math.inf
    thi = math.inf
    for ax in range(3):
        o = ro[p, ax]
        q = float(x0 if ax == 0 else (y0 if ax == 1 else z0))
        q1 = q + (sx if ax == 0 else (sy if ax == 1 else sz))
        if rd[dp, ax] == 0.0:
            cells = ncx if ax == 0 else (ncy if ax == 1 else ncz)
            if o < q or o > q1 or (o == q1 and q1 < cells):
                return 0.0, -math.inf
        else:
            inv = ri[dp, ax]
            ta = (q - o) * inv
            tb = (q1 - o) * inv
            if ta > tb:
                ta, tb = tb, ta
            tlo = max(tlo, ta)
            thi = min(thi, tb)
    return tlo, thi


@njit(nogil=True, cache=True, inline="always")
def _first_sample(t0, first, h, ns, last, k0, tlo):
    """The ray's first sample at or after tlo, starting from its depth indicator k0 (the samples of
    cells skipped since, transparent or occluded, are passed by a guess and a short walk)."""
    kk = k0
    if sample_t(t0, first, h, ns, last, kk) < tlo:
        guess = int(math.ceil((tlo - t0 - first) / h + 0.5))
        if guess > kk:
            kk = min(guess, ns)
        while kk < ns and sample_t(t0, first, h, ns, last, kk) < tlo:
            kk += 1
        while kk > k0 and sample_t(t0, first, h, ns, last, kk - 1) >= tlo:
            kk -= 1
    return kk


@njit(nogil=True, cache=True, inline="always")
def _half_vector(rwd, p, shading):
    """Blinn-Phong's half vector of pixel p's view direction and the headlight (`ShadeParams`)."""
    return headlight_half_vector(shading.lx, shading.ly, shading.lz, rwd[p, 0], rwd[p, 1], rwd[p, 2])


@njit(nogil=True, cache=True, inline="always")
def _post_rgba(tables, use_post, s, length, shaded, fd, sp, frame):
    """Premultiplied (r, g, b, alpha) of a post-classified piece of `length` at value s, shaded with
    (fd, sp) when `shaded`: for a full step from `tables.post`, the TF sampled evenly with the opacity
    already corrected to the step h (a lookup instead of a search over the breakpoints and an exp and
    a log per sample: every sample but a ray's first and last stands for exactly h); exactly otherwise."""
    post = tables.post
    h = frame.h
    if use_post and length == h:
        n = post.shape[0]
        fi = min(max((s - tables.post_lo) * tables.post_scale, 0.0), n - 1.0)
        i0 = min(int(fi), n - 2)
        w = fi - i0
        alpha = post[i0, 3] + w * (post[i0 + 1, 3] - post[i0, 3])
        if alpha <= 0.0:
            return 0.0, 0.0, 0.0, 0.0
        r = post[i0, 0] + w * (post[i0 + 1, 0] - post[i0, 0])
        g = post[i0, 1] + w * (post[i0 + 1, 1] - post[i0, 1])
        b = post[i0, 2] + w * (post[i0 + 1, 2] - post[i0, 2])
        if shaded:  # unshaded, the table's colours lie in [0, 1] already: 5-6 % of phantom_ct's frame
            r = _clamp01(r * fd + sp)
            g = _clamp01(g * fd + sp)
            b = _clamp01(b * fd + sp)
        return r * alpha, g * alpha, b * alpha, alpha
    if length <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    r, g, b, a = tf_lookup(tables.xs, tables.tab, s)
    if a <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    alpha = -math.expm1(length / frame.du * math.log1p(-min(a, MAX_OPACITY)))
    r = _clamp01(r * fd + sp)
    g = _clamp01(g * fd + sp)
    b = _clamp01(b * fd + sp)
    return r * alpha, g * alpha, b * alpha, alpha


@njit(nogil=True, cache=True, inline="always")
def _pixel_post(ray, kk, thi, blk, use_post, tables, frame, shading, rgba, scratch):
    """Composite, post-classified: the `PixelRay`'s samples kk.. with t < thi in the current cell,
    front to back. The pixel's colour stays in registers for the cell (one load and one store instead
    of a read-modify-write of memory per sample). Returns (next sample, samples taken, 1 if it saturated)."""
    p, ox, oy, oz, dx, dy, dz, hx, hy, hz, t0, first, last, ns = ray
    c8 = scratch.c8
    g8 = scratch.g8
    shade = shading.on
    h = frame.h
    term = frame.term
    r = rgba[p, 0]
    g = rgba[p, 1]
    b = rgba[p, 2]
    a = rgba[p, 3]
    taken = 0
    saturated = 0
    while kk < ns:
        t = sample_t(t0, first, h, ns, last, kk)
        if t >= thi:
            break
        visible, base, fx, fy, fz = _locate_in(blk, ox + t * dx, oy + t * dy, oz + t * dz)
        if not visible:  # in a cell the TF leaves transparent: no sample, as in cell order
            kk += 1
            continue
        s = _trilinear_at(c8, base, fx, fy, fz)
        taken += 1
        fd = 1.0
        sp = 0.0
        if shade:
            fd, sp = _light(_trilinear_at_g(g8, 0, base, fx, fy, fz), _trilinear_at_g(g8, 1, base, fx, fy, fz),
                            _trilinear_at_g(g8, 2, base, fx, fy, fz), hx, hy, hz, shading)  # fmt: skip
        if not np.isfinite(s):  # a cell of the block with a non-finite corner: transparent
            kk += 1
            continue
        cr, cg, cb, ca = _post_rgba(tables, use_post, s, segment_length(first, last, h, ns, kk), shade, fd, sp,
                                     frame)  # fmt: skip
        if ca > 0.0:
            tr = 1.0 - a
            r += tr * cr
            g += tr * cg
            b += tr * cb
            a += tr * ca
        kk += 1
        if a >= term:  # term is 2 without hidden volume removal
            saturated = 1
            break
    rgba[p, 0] = r
    rgba[p, 1] = g
    rgba[p, 2] = b
    rgba[p, 3] = a
    return kk, taken, saturated


@njit(nogil=True, cache=True, inline="always")
def _pixel_mixed(ray, kk, thi, blk, ro, grid, classes, frame, rgba):
    """Composite, post-classified, of a label or multi-channel volume: the `PixelRay`'s samples kk..
    with t < thi in the current cell, front to back, each classified by `mixed_rgba` at its point in
    the grid (the shared kernels read the corners they need: a label cell's classes, every channel).
    Samples in cells the classification leaves transparent are not taken, as in `_pixel_post`.
    Returns (next sample, samples taken, 1 if it saturated)."""
    p, ox, oy, oz, dx, dy, dz, hx, hy, hz, t0, first, last, ns = ray
    vol = grid.values
    h = frame.h
    term = frame.term
    gx = ro[p, 0]
    gy = ro[p, 1]
    gz = ro[p, 2]
    r = rgba[p, 0]
    g = rgba[p, 1]
    b = rgba[p, 2]
    a = rgba[p, 3]
    taken = 0
    saturated = 0
    while kk < ns:
        t = sample_t(t0, first, h, ns, last, kk)
        if t >= thi:
            break
        visible, base, fx, fy, fz = _locate_in(blk, ox + t * dx, oy + t * dy, oz + t * dz)
        if not visible:  # in a cell where no visible label or drawn channel has opacity
            kk += 1
            continue
        taken += 1
        cr, cg, cb, ca = mixed_rgba(vol, classes, gx + t * dx, gy + t * dy, gz + t * dz,
                                    segment_length(first, last, h, ns, kk))  # fmt: skip
        if ca > 0.0:
            tr = 1.0 - a
            r += tr * cr
            g += tr * cg
            b += tr * cb
            a += tr * ca
        kk += 1
        if a >= term:  # term is 2 without hidden volume removal
            saturated = 1
            break
    rgba[p, 0] = r
    rgba[p, 1] = g
    rgba[p, 2] = b
    rgba[p, 3] = a
    return kk, taken, saturated


@njit(nogil=True, cache=True, inline="always")
def _pixel_pre(ray, kk, thi, blk, grid, rays, tables, frame, shading, state, scratch):
    """Composite, pre-integrated: the `PixelRay`'s samples kk.. with t < thi in the current cell, each
    closing the segment from the ray's previous sample. Returns (next sample, samples taken, 1 if it
    saturated). Inlined into the walk like `_pixel_post` (numba inlines a call of at most 30 arguments,
    a bundle counting as one): as a call, its 36 arguments (an array is passed as seven words) cost
    more than its samples, bonsai's smooth TF at step 0.5 taking 1.5 s instead of 0.4 s post-classified."""
    p, ox, oy, oz, dx, dy, dz, hx, hy, hz, t0, first, last, ns = ray
    shade = shading.on
    ro = rays.origin
    rgba = state.rgba
    prev_s = state.prev_s
    prev_k = state.prev_k
    prev_fd = state.prev_fd
    prev_sp = state.prev_sp
    c8 = scratch.c8
    g8 = scratch.g8
    e8 = scratch.e8
    eg8 = scratch.eg8
    h = frame.h
    term = frame.term
    taken = 0
    while kk < ns:
        t = sample_t(t0, first, h, ns, last, kk)
        if t >= thi:
            break
        visible, base, fx, fy, fz = _locate_in(blk, ox + t * dx, oy + t * dy, oz + t * dz)
        if not visible:  # in a cell the TF leaves transparent: no sample, as in cell order
            kk += 1
            continue
        s = _trilinear_at(c8, base, fx, fy, fz)
        taken += 1
        fd = 1.0
        sp = 0.0
        if shade:
            fd, sp = _light(_trilinear_at_g(g8, 0, base, fx, fy, fz), _trilinear_at_g(g8, 1, base, fx, fy, fz),
                            _trilinear_at_g(g8, 2, base, fx, fy, fz), hx, hy, hz, shading)  # fmt: skip
        finite = np.isfinite(s)  # not: a cell of the block with a non-finite corner, transparent
        if kk == 0 and finite:  # from the ray's entry point (on the box) to its first sample
            _edge(ray, t0, Sample(s, fd, sp), t - t0, True, grid, ro, tables, frame, shading, rgba, scratch)
        elif kk > 0 and finite:
            tp = sample_t(t0, first, h, ns, last, kk - 1)
            if prev_k[p] == kk - 1:
                sf = prev_s[p]
                fd_f = prev_fd[p]
                sp_f = prev_sp[p]
            else:  # the previous sample lies in a skipped cell: fetch it
                px = ro[p, 0] + tp * dx
                py = ro[p, 1] + tp * dy
                pz = ro[p, 2] + tp * dz
                sf = _fetch(grid, px, py, pz, e8, eg8)
                fd_f = 1.0
                sp_f = 0.0
                if shade and np.isfinite(sf):
                    fd_f, sp_f = _fetch_light(grid, px, py, pz, hx, hy, hz, shading, e8, eg8)
            if np.isfinite(sf):
                _segment(rgba, p, Sample(sf, fd_f, sp_f), Sample(s, fd, sp), t - tp, h, shade, tables)
        if kk == ns - 1 and finite:  # from the last sample to the ray's exit point
            t_end = ray_end(t0, first, h, ns, last)
            _edge(
                ray,
                t_end,
                Sample(s, fd, sp),
                t_end - t,
                False,
                grid,
                ro,
                tables,
                frame,
                shading,
                rgba,
                scratch,
            )
        prev_s[p] = s
        prev_k[p] = kk
        prev_fd[p] = fd
        prev_sp[p] = sp
        kk += 1
        if rgba[p, 3] >= term:
            return kk, taken, 1
    return kk, taken, 0


@njit(nogil=True, cache=True, inline="always")
def _pixel_project(ray, kk, tlo, thi, c8, frame, acc):
    """Maximum, minimum and average: the `PixelRay`'s samples kk.. with t < thi in the current cell
    (t >= tlo; the cell's grid points in `c8` as `_load_block` lays them out). Returns (next sample,
    samples taken, 0)."""
    p, ox, oy, oz, dx, dy, dz, hx, hy, hz, t0, first, last, ns = ray
    mode = frame.mode
    h = frame.h
    taken = 0
    if mode == MAXIMUM or mode == MINIMUM:  # the ray's entry and exit points of the cell
        t_end = ray_end(t0, first, h, ns, last)
        te = max(tlo, t0)
        tx = min(thi, t_end)
        if te < tx and ns > 0:
            for end in range(2):
                tt = te if end == 0 else tx
                v = _trilinear_at(
                    c8, 0, _clamp01(ox + tt * dx), _clamp01(oy + tt * dy), _clamp01(oz + tt * dz)
                )
                if mode == MAXIMUM:
                    acc[p, 0] = max(acc[p, 0], v)
                else:
                    acc[p, 0] = min(acc[p, 0], v)
                acc[p, 1] = 1.0
    while kk < ns:
        t = sample_t(t0, first, h, ns, last, kk)
        if t >= thi:
            break
        s = _trilinear_at(c8, 0, _clamp01(ox + t * dx), _clamp01(oy + t * dy), _clamp01(oz + t * dz))
        length = segment_length(first, last, h, ns, kk)
        taken += 1
        if mode == AVERAGE:
            acc[p, 0] += s * length
            acc[p, 1] += length
        elif mode == MAXIMUM:
            acc[p, 0] = max(acc[p, 0], s)
            acc[p, 1] = 1.0
        else:
            acc[p, 0] = min(acc[p, 0], s)
            acc[p, 1] = 1.0
        kk += 1
    return kk, taken, 0


@njit(nogil=True, cache=True, inline="always")
def _finished_pixel(finished, q0, q1, c0, c1, width):
    """Whether a pixel of rows q0..q1, columns c0..c1 is finished (opaque, or its ray done)."""
    for r in range(q0, q1 + 1):
        for p in range(r * width + c0, r * width + c1 + 1):
            if finished[p]:
                return True
    return False


@njit(nogil=True, cache=True, inline="always")
def _node_rect(view, grid, lv, i, j, k, r0, r1):
    """(c0, c1, q0, q1, own): the columns and the band's rows r0..r1 - 1 (q0 > q1: none) of node
    (lv, i, j, k)'s footprint in the `View`, and 1 when the band holds its middle row (it counts the node)."""
    M = view.M
    width = view.width
    height = view.height
    ncx = grid.ncx
    ncy = grid.ncy
    ncz = grid.ncz
    size = 1 << lv
    x0 = i * size
    y0 = j * size
    z0 = k * size
    x1 = min(x0 + size, ncx)
    y1 = min(y0 + size, ncy)
    z1 = min(z0 + size, ncz)
    if view.perspective:
        c0, c1, fr0, fr1 = footprint(M, float(x0), float(y0), float(z0), float(x1), float(y1), float(z1),
                                     width, height)  # fmt: skip
    else:
        c0, c1, fr0, fr1 = footprint_affine(M, float(x0), float(y0), float(z0), float(x1), float(y1), float(z1),
                                            width, height)  # fmt: skip
    if c0 > c1 or fr0 > fr1:
        return 0, -1, 1, 0, 0
    mid = (fr0 + fr1) // 2
    return c0, c1, max(fr0, r0), min(fr1, r1 - 1), 1 if (mid >= r0 and mid < r1) else 0


@njit(nogil=True, cache=True, inline="always")
def _block(at, rect, r0, grid, view, rays, tables, frame, shading, state, occlusion, scratch, classes):
    """The `CellBlock` of up to size^3 leaf cells from cell (x0, y0, z0), `cells` = bits + 256 size: size 1
    (a cell) or 2 (an octree node one level above the cells); its grid points loaded once, then the
    samples of every unfinished pixel of the `Rect` (rows q0..q1 of the band from r0) that lie in it, none in the
    cells the TF leaves transparent (bits: the octree's leaf bits, x + 2 y + 4 z). Returns (samples
    taken, pixels saturated). The walk calls it from one place, so that it is compiled once, with its
    pixel loops inlined (two copies, one per size, had doubled the plugin's compile time).

    Why blocks: the footprint, the occlusion test, the loads and the slab tests are then paid once for
    up to eight cells, and a pixel's slab test once for the cells of the block it crosses (the block's
    footprint rectangle holds about a third of the pixels of its cells' rectangles at 1-2 pixels a
    voxel); the samples, and so the image, are the cells' own. The walk takes cells one by one where
    the occlusion map may hide some of them (`_walk_band`). The arrays come in bundles: numba inlines a
    call of at most 30 arguments only (more are passed as *args). `classes`: the frame's label or
    channel classification (`mixed_samples`; its samples replace the post-classified ones), or `PLAIN`."""
    x0, y0, z0, cells = at
    c0, c1, q0, q1 = rect
    ncx = grid.ncx
    ncy = grid.ncy
    ncz = grid.ncz
    width = view.width
    ro, rd, rwd, ri, rt0, rcount, rfirst, rlast = rays
    rgba = state.rgba  # the previous samples are `_pixel_pre`'s
    acc = state.acc
    nextk = state.nextk
    finished = state.finished
    hom, hl, hoff, hcols = occlusion
    c8 = scratch.c8
    g8 = scratch.g8
    mode = frame.mode
    shade = shading.on
    hvr = frame.hvr and mode == COMPOSITE
    use_post = tables.post.shape[0] > 1
    shared = rd.shape[0] == 1  # one direction for every ray (a parallel projection, `RayTable`)
    h = frame.h
    term = frame.term
    post_path = mode == COMPOSITE and not frame.pre
    n_samples = 0
    n_saturated = 0
    bits = cells & 255
    size = cells >> 8
    sx = min(size, ncx - x0)
    sy = min(size, ncy - y0)
    sz = min(size, ncz - z0)
    blk = (np.int64(bits), np.int64(sx), np.int64(sy), np.int64(sz), np.int64(size))  # one type: indexable
    if not is_mixed(classes):  # the mixed samples read the grid themselves
        _load_block(grid, x0, y0, z0, sx, sy, sz, shade, c8, g8)
    for r in range(q0, q1 + 1):
        for c in range(c0, c1 + 1):
            p = r * width + c
            if finished[p]:
                continue
            dp = 0 if shared else p
            tlo, thi = _slab(rays, grid, p, dp, x0, y0, z0, sx, sy, sz)
            if not thi > tlo:
                continue
            ns = rcount[p]
            t0 = rt0[p]
            first = rfirst[p]
            last = rlast[p]
            kk = _first_sample(t0, first, h, ns, last, nextk[p], tlo)
            dx = rd[dp, 0]
            dy = rd[dp, 1]
            dz = rd[dp, 2]
            ox = ro[p, 0] - x0
            oy = ro[p, 1] - y0
            oz = ro[p, 2] - z0
            hx = hy = hz = 0.0
            if shade:
                hx, hy, hz = _half_vector(rwd, dp, shading)
            ray = PixelRay(p, ox, oy, oz, dx, dy, dz, hx, hy, hz, t0, first, last, ns)
            if post_path and is_mixed(classes):
                kk, taken, sat = _pixel_mixed(ray, kk, thi, blk, ro, grid, classes, frame, rgba)
            elif post_path:
                kk, taken, sat = _pixel_post(
                    ray, kk, thi, blk, use_post, tables, frame, shading, rgba, scratch
                )
            elif mode == COMPOSITE:
                kk, taken, sat = _pixel_pre(
                    ray, kk, thi, blk, grid, rays, tables, frame, shading, state, scratch
                )
            else:
                kk, taken, sat = _pixel_project(ray, kk, tlo, thi, c8, frame, acc)
            n_samples += taken
            n_saturated += sat
            nextk[p] = kk
            if kk >= ns or (hvr and rgba[p, 3] >= term):
                finished[p] = 1
                hom_finish(hom, hl, hoff, hcols, r - r0, c)
    return n_samples, n_saturated


@njit(nogil=True, cache=True)
def render_band(band, grid, octree, view, rays, tables, frame, shading, state, classes):
    """The `Band`'s rows (`_walk_band`), with the band's scratch arrays allocated here: the walk is
    compiled without numba's reference counting, which otherwise left atomic increments and
    decrements of shared arrays' counts in the per-pixel loop (slow on one thread, and the two
    threads fought over those counters' cache lines)."""
    rows = band.r1 - band.r0
    hl, hoff, hcols, hsize = hom_layout(rows, view.width)
    hom = np.empty(hsize, np.int32)
    depth = 8 * octree.shapes.shape[0] + 8
    stack = np.empty((depth, 4), np.int64)
    c8 = np.empty(27)  # a block's grid points (`_load_block`)
    g8 = np.zeros((27, 3))
    e8 = np.empty(27)  # one cell's grid points for `_fetch`, as `_load_block` lays them out
    eg8 = np.zeros((27, 3))
    _walk_band(band, grid, octree, view, rays, tables, frame, shading, state, Occlusion(hom, hl, hoff, hcols),
               Scratch(stack, c8, g8, e8, eg8), classes)  # fmt: skip


@njit(nogil=True, cache=True, _nrt=False)
def _walk_band(band, grid, octree, view, rays, tables, frame, shading, state, occlusion, scratch, classes):
    """The `Band`'s rows r0..r1 - 1: walk the `Octree` front to back, skipping transparent nodes and (with hidden
    volume removal) nodes on finished pixels, and sample every leaf cell's rays. The counters are
    kept in locals and written once at the end (`stats` rows of neighbouring bands share cache
    lines: an increment per sample there made the two threads fight over them)."""
    r0, r1, stats = band
    counts, offsets, shapes, leaves = octree
    width = view.width
    perspective = view.perspective
    eye = view.eye
    vdir = view.vdir
    rcount = rays.n_samples
    rgba = state.rgba
    nextk = state.nextk
    finished = state.finished
    hom, hl, hoff, hcols = occlusion
    stack = scratch.stack
    mode = frame.mode
    hvr = frame.hvr and mode == COMPOSITE
    # a node above the cells with at most this many pixels, none finished, and at least 4 of its 8 cells
    # visible is drawn as one block (`_block`); larger ones, whose cells' overheads many pixels share
    # already, and sparse ones (a block's footprint and slab tests cost more than a few cells' own), cell
    # by cell
    block_pixels = frame.block_pixels if mode == COMPOSITE else 0  # maximum, minimum, average: cell by cell
    rows = r1 - r0
    hom_init(hom, hl, hoff, hcols, rows, width)
    for p in range(
        r0 * width, r1 * width
    ):  # the band's pixels start clear (buffers are reused across frames)
        rgba[p, 0] = 0.0
        rgba[p, 1] = 0.0
        rgba[p, 2] = 0.0
        rgba[p, 3] = 0.0
        nextk[p] = 0
        finished[p] = 0
        if rcount[p] == 0:
            finished[p] = 1
            hom_finish(hom, hl, hoff, hcols, p // width - r0, p % width)
    levels = shapes.shape[0]
    stack[0, 0] = levels - 1  # (level, i, j, k) of the nodes still to visit, the nearest on top
    stack[0, 1] = 0
    stack[0, 2] = 0
    stack[0, 3] = 0
    top = 1
    n_nodes = 0
    n_cells = 0
    n_occ_cells = 0
    n_occ_nodes = 0
    n_samples = 0
    n_saturated = 0
    while top > 0:
        top -= 1
        lv = stack[top, 0]
        i = stack[top, 1]
        j = stack[top, 2]
        k = stack[top, 3]
        # level 0's counts are the leaf bits of level 1 (pushed only when visible), but a one-cell grid's root
        count = (
            1 if lv == 0 and levels > 1 else counts[offsets[lv] + (k * shapes[lv, 1] + j) * shapes[lv, 2] + i]
        )
        if count == 0:
            continue
        c0, c1, q0, q1, own = _node_rect(view, grid, lv, i, j, k, r0, r1)
        if q0 > q1:
            continue
        n_nodes += own
        # a cell's footprint is tested against the map even without hidden volume removal (pixels whose
        # rays have ended are finished too)
        if (hvr or lv == 0) and hom_covered(hom, hl, hoff, hcols, q0 - r0, q1 - r0, c0, c1):
            n_occ_cells += count * own
            n_occ_nodes += own
            continue
        if lv == 0:  # a leaf cell (pushed by its level-1 node, below) or the root of a one-cell grid
            cells = 256 + 1
            x0, y0, z0 = i, j, k
        elif lv == 1 and count >= 4 and (q1 - q0 + 1) * (c1 - c0 + 1) <= block_pixels and not (
                hvr and _finished_pixel(finished, q0, q1, c0, c1, width)):  # fmt: skip
            # no pixel of its footprint is finished: none of its cells is hidden
            cells = 512 + leaves[k, j, i]
            x0, y0, z0 = 2 * i, 2 * j, 2 * k
        else:  # its children onto the stack, farthest first: the nearest is visited next
            mask = child_order_mask(lv, i, j, k, perspective, eye, vdir)
            bits8 = leaves[k, j, i] if lv == 1 else 0
            cl = lv - 1
            for n in range(7, -1, -1):
                bits = n ^ mask
                if lv == 1 and not (bits8 >> bits) & 1:  # a cell the TF leaves transparent
                    continue
                ci = 2 * i + (bits & 1)
                cj = 2 * j + ((bits >> 1) & 1)
                ck = 2 * k + (bits >> 2)
                if ci < shapes[cl, 2] and cj < shapes[cl, 1] and ck < shapes[cl, 0]:
                    stack[top, 0] = cl
                    stack[top, 1] = ci
                    stack[top, 2] = cj
                    stack[top, 3] = ck
                    top += 1
            continue
        n_cells += count * own
        taken, sat = _block(CellBlock(x0, y0, z0, cells), Rect(c0, c1, q0, q1), r0, grid, view, rays, tables, frame,
                            shading, state, occlusion, scratch, classes)  # fmt: skip
        n_samples += taken
        n_saturated += sat
    stats[S_NODES] += n_nodes
    stats[S_CELLS] += n_cells
    stats[S_OCCLUDED_CELLS] += n_occ_cells
    stats[S_OCCLUDED_NODES] += n_occ_nodes
    stats[S_SAMPLES] += n_samples
    stats[S_SATURATED] += n_saturated


@njit(nogil=True, cache=True, parallel=True)
def render_bands(bands, band_rows, grid, octree, view, rays, tables, frame, shading, state, stats, classes):
    """The bands listed in `bands` (of band_rows rows each; counters in stats[band]), in parallel
    (each band's rows belong to it alone), lit with the frame's `ShadeParams` `shading` (its own
    parameter, no bundle's member: numba's parallel loops take a bundle apart one level only), and with
    `classes` (`mixed_samples.PLAIN`, or a label or channel classification drawn post-classified)."""
    for q in prange(bands.shape[0]):
        b = bands[q]
        r0 = b * band_rows
        r1 = min(view.height, r0 + band_rows)
        render_band(Band(r0, r1, stats[b]), grid, octree, view, rays, tables, frame, shading, state, classes)


@njit(nogil=True, cache=True, parallel=True)
def finish(rgba, out):
    """The composited pixels as the image: clamped to [0, 1], colour at most opacity, float32, in
    one parallel pass (numpy takes four passes over the float64 pixels)."""
    for p in prange(rgba.shape[0]):
        a = _clamp01(rgba[p, 3])
        for c in range(3):
            out[p, c] = min(_clamp01(rgba[p, c]), a)
        out[p, 3] = a
