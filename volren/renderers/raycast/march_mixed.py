"""The numba march of label and multi-channel volumes: each sample classified by several TFs.

Why a march of its own: a label volume's sample blends the TFs of its cell's corner labels
(`volren.kernels.label_sample`), a multi-channel volume's adds every channel's
(`volren.kernels.channel_sample`), both through `volren.kernels.mixed_sample`; neither is a
lookup of one value in one table, which the plain march (`march`) is built around. Samples lie
where the plain post-classified march puts them (`volren.kernels.sample_placement`, the midpoint
of each segment), so a scene that reduces to one TF gives the plain march's image; a sample whose
brick is empty (no visible label or channel with opacity in the brick's range) is skipped before
anything is read, so hidden labels and channels cost no samples. Rays stop once opaque. The C
march (`march.c`) draws the same samples with a brick walk and eight samples at a time.
"""

from __future__ import annotations

from numba import njit, prange

from volren.kernels.clip_planes import clip_entry
from volren.kernels.mixed_sample import sample_rgba
from volren.kernels.sample_placement import ray_segment, ray_segments
from volren.renderers.raycast.march import FAST, _brick_shift, _pixel_ray, _store
from volren.renderers.raycast.march_inputs import TILE


@njit(nogil=True, cache=True, inline="always", fastmath=FAST)
def _ray(vol, bricks, shift, view, xx, ny_, phase, classes, term):
    """(r, g, b, a, samples, skipped, terminated): pixel column xx's ray at NDC y ny_ marched front
    to back, each segment's middle classified (`sample_rgba`); segments whose brick is empty are
    skipped before anything is read (`skipped`)."""
    empty, B = bricks.distance, bricks.size
    view_dir, t_far_eye, h = view.view_dir, view.far_depth, classes.step
    nz, ny, nx = vol.shape
    ox, oy, oz, dx, dy, dz, ix, iy, iz, wx, wy, wz, t_in, t_out, miss = _pixel_ray(
        view, xx, ny_, nx - 1.0, ny - 1.0, nz - 1.0
    )
    t_far = t_far_eye / (wx * view_dir[0] + wy * view_dir[1] + wz * view_dir[2])
    t0, t1, _ = clip_entry(ox, oy, oz, dx, dy, dz, view.planes, max(t_in, 0.0), min(t_out, t_far))
    r = 0.0
    g = 0.0
    b = 0.0
    a = 0.0
    if miss or not t1 > t0:
        return r, g, b, a, 0, 0, 0
    ns, first, last = ray_segments(t1 - t0, h, (phase - t0 / h) % 1.0)
    taken = 0
    skipped = 0
    for k in range(ns):
        tk, lk = ray_segment(t0, first, last, h, ns, k)
        tm = tk + 0.5 * lk
        px = ox + tm * dx
        py = oy + tm * dy
        pz = oz + tm * dz
        bi = min(max(int(px), 0), nx - 2)
        bj = min(max(int(py), 0), ny - 2)
        bk = min(max(int(pz), 0), nz - 2)
        if shift >= 0:
            bi, bj, bk = bi >> shift, bj >> shift, bk >> shift
        else:
            bi, bj, bk = bi // B, bj // B, bk // B
        if empty[bk, bj, bi] != 0:
            skipped += 1
            continue
        taken += 1
        cr, cg, cb, ca = sample_rgba(vol, classes, px, py, pz, lk)
        if ca > 0.0:
            tr = 1.0 - a
            r += tr * cr
            g += tr * cg
            b += tr * cb
            a += tr * ca
            if a >= term:
                return r, g, b, a, taken, skipped, 1 if k < ns - 1 else 0
    return r, g, b, a, taken, skipped, 0


@njit(nogil=True, cache=True, parallel=True, fastmath=FAST)
def march_mixed(vol, bricks, view, classes, term, tiles, out, counts):
    """`march.march` for label and multi-channel volumes: the tiles `tiles` of the `PixelView` view
    into `out`, `counts[tile]` = (samples, jumps (none), segments skipped, rays terminated early);
    `classes`: a `LabelClassification` or a `ChannelClassification`."""
    width, height, phases = view.width, view.height, view.phases
    tiles_x = (width + TILE - 1) // TILE
    shift = _brick_shift(bricks.size)
    for q in prange(tiles.shape[0]):
        tile = tiles[q]
        x_start = (tile % tiles_x) * TILE
        y_start = (tile // tiles_x) * TILE
        taken = 0
        skipped = 0
        stopped = 0
        for yy in range(y_start, min(y_start + TILE, height)):
            ny_ = 1.0 - (yy + 0.5) / height * 2.0
            for xx in range(x_start, min(x_start + TILE, width)):
                p = yy * width + xx
                r, g, b, a, n, sk, st = _ray(vol, bricks, shift, view, xx, ny_, phases[p], classes, term)
                taken += n
                skipped += sk
                stopped += st
                _store(out, p, r, g, b, a)
        counts[tile, 0] = taken
        counts[tile, 1] = 0
        counts[tile, 2] = skipped
        counts[tile, 3] = stopped


@njit(nogil=True, cache=True, parallel=True, fastmath=FAST)
def march_mixed_pixels(vol, bricks, view, classes, term, pixels, out, counts):
    """As `march_mixed`, for the listed pixels (row-major indices) only (`march.march_pixels`)."""
    width, height, phases = view.width, view.height, view.phases
    shift = _brick_shift(bricks.size)
    for q in prange(pixels.shape[0]):
        p = pixels[q]
        yy = p // width
        ny_ = 1.0 - (yy + 0.5) / height * 2.0
        r, g, b, a, n, sk, st = _ray(vol, bricks, shift, view, p - yy * width, ny_, phases[p], classes, term)
        counts[q, 0] = n
        counts[q, 1] = 0
        counts[q, 2] = sk
        counts[q, 3] = st
        _store(out, q, r, g, b, a)
