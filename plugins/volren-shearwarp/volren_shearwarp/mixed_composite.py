"""The compositing kernel of label and multi-channel volumes: the slabs of `composite`, each segment's
two ends classified per sample (`volren.kernels.mixed_sample.sample_rgba`).

Why its own kernel: the plain kernels classify a segment by its end values alone, in one table per
segment length. With labels a sample's classification also depends on where it lies in its cell
(the corner classes blended by their trilinear weights, Real-Time Volume Graphics section 16.5),
and with channels on several scalars (their extinctions added, Max 1995): neither is a function of
one scalar, so neither fits a 1D LUT or a pre-integration table. Shear-warp's slices still give
the sample points: the ray through intermediate pixel (q, p) meets slice k at (a, b) =
(alpha_a[k] + beta_a[k] p, alpha_b[k] + beta_b[k] q), so each sample is classified at the index
point (a, b, c) of the axis copies (labels, cell classes and channels laid out like the values),
and the segment is composited as the post-classified plain path does (`composite._segment`): the
front half with the front sample, the back half with the back sample, each corrected to half the
segment's length, and a partial segment's sum corrected to its part (Schulze et al. 2003). So a
label scene whose labels all draw alike gives the plain post-classified image with bilinear lookups.

Kept from `composite_slabs`: blocks of rows, the run-length runs of possibly visible blocks
(here over the union of the classes' or channels' opacity supports, hidden labels masked out),
skip links (early termination), sub-planes (`step` below 0.5), strided slabs, a short last slab, and
the near / far planes and clip region (a cut segment sampled at the cut). Not kept: the fast spans
(each sample reads its cell's class), shading and jitter (refused by the renderer).
"""

from __future__ import annotations

import math

from numba import njit, prange

from volren.kernels.mixed_sample import sample_rgba
from volren_shearwarp.composite import (
    _clip,
    _first_past,
    _forward_split,
    _guess,
    _next_open,
    _pixel_range,
    _sub_interval,
)


@njit(nogil=True, cache=True, inline="always", error_model="numpy")
def _sample(vol, classes, kf, kb, w, a, b, top_a, top_b, half):
    """Premultiplied RGBA of half a segment (`half` world units) at plane w between slices kf and kb
    and in-plane (a, b), clamped to the slice rectangle as `composite.bilinear` clamps its samples."""
    a = min(max(a, 0.0), top_a)
    b = min(max(b, 0.0), top_b)
    c = kf + w * (kb - kf)
    return sample_rgba(vol, classes, a, b, c, half)


@njit(nogil=True, parallel=True, cache=True, error_model="numpy")
def composite_classes(
    geom, m0, m1, rgba, front, stamp, skip, counters, classes, halves, runs, termination, clip
):
    """Composite slabs m in [m0, m1) (`SlabGeometry`, as `composite.composite_slabs`) of a label or
    channel scene into `rgba` (premultiplied, float32), clearing each row first when m0 <= 1.
    classes: a `LabelClassification` or `ChannelClassification` on the axis copy's grid (index
    (a, b, c)); halves[q, p]: half of pixel (q, p)'s whole segment length (world units); front:
    (h, w, 4) the back sample of the pixel's last segment, valid where stamp says its sub-plane.
    counters[q] += (segments composited, pixels skipped as empty, pixels terminated)."""
    vol = geom.values
    order = geom.order
    sub = geom.planes
    alpha_a = geom.alpha_a
    beta_a = geom.beta_a
    alpha_b = geom.alpha_b
    beta_b = geom.beta_b
    rows = geom.rows
    row_block = geom.row_block
    slab_frac = geom.slab_frac
    use_runs, offsets, starts, ends, extent, run_slab = runs
    use_termination, term_alpha = termination
    clipping, clip_lo, clip_hi = clip
    nc, nb, na = vol.shape
    width = rgba.shape[1]
    inv_sub = 1.0 / sub
    top_a = na - 1.0
    top_b = nb - 1.0
    for block in prange((rows.shape[0] + row_block - 1) // row_block):
        r0 = block * row_block
        r1 = min(r0 + row_block, rows.shape[0])
        if m0 <= 1:
            for r in range(r0, r1):
                q = rows[r]
                rgba[q, :, :] = 0.0
                stamp[q, :] = -1
                skip[q, :] = 0
                counters[q, :] = 0
        n_comp = 0
        n_empty = 0
        n_term = 0
        for m in range(max(m0, 1), m1):
            kf = order[m - 1]
            kb = order[m]
            slab = run_slab[m]
            whole = slab_frac[m]
            u_f = float(abs(kf - order[0]))
            u_span = float(abs(kb - order[0])) - u_f
            af0 = alpha_a[kf]
            afs = beta_a[kf]
            ab0 = alpha_a[kb]
            abs_ = beta_a[kb]
            p_lo, p_hi = _pixel_range(af0, afs, ab0, abs_, top_a)
            p_lo = max(p_lo, 0)
            p_hi = min(p_hi, width)
            if p_lo >= p_hi:
                continue
            for r in range(r0, r1):
                q = rows[r]
                bf = alpha_b[kf] + beta_b[kf] * q
                bb = alpha_b[kb] + beta_b[kb] * q
                if max(bf, bb) < 0.0 or min(bf, bb) > top_b:
                    continue
                first = 0
                n_runs = 1
                parts = 1
                split = 0
                forward_above = True
                if use_runs:  # the anchored blocks of `classified`, as `composite_slabs` takes them
                    jb = int(math.floor(bf)) + (extent if bb >= bf else 0)
                    jb = min(max(jb, 0), nb - 2 + extent)
                    first = offsets[slab * (nb - 1 + extent) + jb]
                    n_runs = offsets[slab * (nb - 1 + extent) + jb + 1] - first
                    parts = 2
                    split, forward_above = _forward_split(af0, afs, ab0, abs_, p_lo, p_hi)
                covered = 0
                for item in range(parts * n_runs):
                    lo_p = p_lo
                    hi_p = p_hi
                    if use_runs:
                        forward = item < n_runs
                        run = first + item % n_runs
                        if forward == forward_above:
                            lo_p = max(lo_p, split)
                        else:
                            hi_p = min(hi_p, split)
                        if lo_p >= hi_p:
                            continue
                        moved = extent if forward else 0
                        a_s = starts[run]
                        a_e = ends[run]
                        if a_s > 0:
                            lo_p = max(
                                lo_p, _first_past(af0, afs, a_s - moved, False, _guess(af0, afs, a_s - moved))
                            )
                        if a_e < na - 1 + extent:
                            hi_p = min(
                                hi_p, _first_past(af0, afs, a_e - moved, False, _guess(af0, afs, a_e - moved))
                            )
                        if lo_p >= hi_p:
                            continue
                        covered += hi_p - lo_p
                    p = lo_p
                    while True:
                        if use_termination:
                            p = _next_open(skip, q, p, hi_p)
                        if p >= hi_p:
                            break
                        af = af0 + afs * p
                        ab = ab0 + abs_ * p
                        t0, t1 = _clip(af, ab, top_a, 0.0, 1.0)
                        t0, t1 = _clip(bf, bb, top_b, t0, t1)
                        v0 = 0.0
                        v1 = 1.0
                        if clipping:
                            v0 = (clip_lo[q, p] - u_f) / u_span
                            v1 = (clip_hi[q, p] - u_f) / u_span
                            t0 = max(t0, v0)
                            t1 = min(t1, v1)
                        if t1 <= t0:
                            p += 1
                            continue
                        half = halves[q, p]
                        for j in range(sub):
                            u0, u1 = _sub_interval(j, inv_sub, t0, t1)
                            if u1 <= u0:
                                continue
                            frac = (u1 - u0) * sub * whole
                            plane = (m - 1) * sub + j
                            w0 = j * inv_sub
                            w1 = (j + 1) * inv_sub if j + 1 < sub else 1.0
                            cut_front = v0 > w0
                            cut_back = v1 < w1
                            if cut_front:
                                w0 = v0
                            if cut_back:
                                w1 = v1
                            if stamp[q, p] == plane and not cut_front:
                                fr = front[q, p, 0]
                                fg = front[q, p, 1]
                                fb = front[q, p, 2]
                                fa = front[q, p, 3]
                            else:
                                fr, fg, fb, fa = _sample(vol, classes, kf, kb, w0, af + w0 * (ab - af),
                                                         bf + w0 * (bb - bf), top_a, top_b, half)  # fmt: skip
                            br, bg, bb_, ba = _sample(vol, classes, kf, kb, w1, af + w1 * (ab - af),
                                                      bf + w1 * (bb - bf), top_a, top_b, half)  # fmt: skip
                            if not cut_back:
                                stamp[q, p] = plane + 1
                                front[q, p, 0] = br
                                front[q, p, 1] = bg
                                front[q, p, 2] = bb_
                                front[q, p, 3] = ba
                            # the front half, then the back half behind it (premultiplied)
                            t = 1.0 - fa
                            cr = fr + t * br
                            cg = fg + t * bg
                            cb = fb + t * bb_
                            alpha = fa + t * ba
                            n_comp += 1
                            if alpha <= 0.0:
                                continue
                            if frac < 1.0:  # partial: Schulze et al.'s opacity and colour correction
                                corrected = -math.expm1(frac * math.log1p(-min(alpha, 1.0 - 1e-7)))
                                factor = corrected / alpha
                                cr *= factor
                                cg *= factor
                                cb *= factor
                                alpha = corrected
                            t = 1.0 - rgba[q, p, 3]
                            rgba[q, p, 0] += t * cr
                            rgba[q, p, 1] += t * cg
                            rgba[q, p, 2] += t * cb
                            rgba[q, p, 3] += t * alpha
                            if use_termination and rgba[q, p, 3] >= term_alpha:
                                skip[q, p] = 1
                                n_term += 1
                                break
                        p += 1
                if use_runs:
                    n_empty += (p_hi - p_lo) - covered
        counters[rows[r0], 0] += n_comp
        counters[rows[r0], 1] += n_empty
        counters[rows[r0], 2] += n_term
