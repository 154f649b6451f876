"""Cell-to-cell ray casting through a tetrahedral mesh (Weiler et al.; Real-Time Volume Graphics, section 7.5), on
the CPU with numba.

Per pixel ray:
1. Entries. The boundary faces turned towards the eye are rasterized to the pixels they cover
   (`entry_bins`), and the cells the near plane cuts are binned by their pixel boxes
   (`volren.kernels.tet_projection.bin_rows`). Where a ray crosses a candidate cell's boundary face inside its
   triangle, or starts inside the cell, it enters the mesh (`_entries`). Entries are sorted by
   their ray parameter.
2. Walk. From an entry the ray leaves each tetrahedron through the face whose plane it meets first
   among those it heads out of (t = -a / b with b < 0), and enters the neighbour across that face.
   The face planes come from the mesh preparation (`PreparedMesh.planes`, packed by
   `pack_planes`): both tetrahedra of a face hold exactly opposite planes, so the exit parameter
   of one is the entry parameter of the other, with no gap and no overlap. A ray lying in a face
   plane belongs to one cell by a symbolic perturbation; a ray through an edge or a vertex leaves
   the cells it only touches at once (zero length) and walks around the edge or vertex to the cell
   it does enter.
3. Leaving the mesh (a face with no neighbour, or one next to a flat or non-finite cell, which
   count as holes) ends the walk; the next entry beyond that point starts the next one, so
   non-convex meshes and holes are handled alike. A walk longer than `max_steps` cells stops and
   is counted.
4. Each cell segment is integrated from its front value, back value and length with the 3D
   pre-integration table (`integrate_segment`). For compositing, the walk may run only through the
   cells the TF makes visible (`walked_cells`): the entry faces are then the visible cells'
   boundary faces, and a walk ends where it would run through a transparent cell, so the next entry
   jumps over the transparent run. A ray stops once its opacity reaches the termination threshold.
5. Clipping: each ray is cut to the part the clip region keeps (`volren.kernels.clip_planes`, the
   far plane included); a cell segment across a cut is integrated from the linear field's value at
   the cut, so the cut surface is flat inside the cells, not their jagged boundary. With cut faces
   (`ClipRegion.cap`) the cell holding the point where a ray enters through a plane gives the
   value there, and an opaque face of the TF's colour ends the ray (`volren.kernels.cut_faces`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from volren.kernels.clip_planes import clip_entry
from volren.kernels.cut_faces import cut_face
from volren.kernels.shading import blinn_phong_factors, headlight_half_vector

COMPOSITE, MAXIMUM, MINIMUM, AVERAGE = 0, 1, 2, 3
#: Entries kept per ray (more are counted and ignored; meshes with this many boundary crossings
#: along one ray are not seen in practice).
MAX_ENTRIES = 512
#: Rays per parallel work item of `cast_rays`: each allocates its entry lists once (three arrays of
#: MAX_ENTRIES per ray had cost an allocation each).
RAY_BLOCK = 16


@njit(nogil=True, cache=True)
def _bilinear(table, i0, j0, fi, fj, c):
    return (1.0 - fi) * ((1.0 - fj) * table[i0, j0, c] + fj * table[i0, j0 + 1, c]) + fi * (
        (1.0 - fj) * table[i0 + 1, j0, c] + fj * table[i0 + 1, j0 + 1, c]
    )


@njit(nogil=True, cache=True)
def integrate_segment(table, s_front, s_back, length):
    """Premultiplied (r, g, b, alpha) of a segment from the 3D table (`SegmentTable`): the optical
    depth is exact in the length (per-length depth, bilinear in the two values), the colour per
    unit opacity is interpolated linearly between the evenly spaced length layers
    (`model.preintegration.lengths`)."""
    depth_per_length, colour_ratio = table.depth_per_length, table.colour_ratio
    lo, scale, lmax = table.lo, table.scale, table.lmax
    n = depth_per_length.shape[0]
    x = min(max((s_front - lo) * scale, 0.0), n - 1.0)
    y = min(max((s_back - lo) * scale, 0.0), n - 1.0)
    i0 = min(int(x), n - 2)
    j0 = min(int(y), n - 2)
    fi = x - i0
    fj = y - j0
    depth = length * _bilinear(depth_per_length, i0, j0, fi, fj, 0)
    alpha = -math.expm1(-depth)
    layers = colour_ratio.shape[0]
    u = min(max(layers * length / lmax - 1.0, 0.0), layers - 1.0)
    k0 = min(int(u), layers - 1)
    k1 = min(k0 + 1, layers - 1)
    w = u - k0
    r = (1.0 - w) * _bilinear(colour_ratio[k0], i0, j0, fi, fj, 0) + w * _bilinear(
        colour_ratio[k1], i0, j0, fi, fj, 0
    )
    g = (1.0 - w) * _bilinear(colour_ratio[k0], i0, j0, fi, fj, 1) + w * _bilinear(
        colour_ratio[k1], i0, j0, fi, fj, 1
    )
    b = (1.0 - w) * _bilinear(colour_ratio[k0], i0, j0, fi, fj, 2) + w * _bilinear(
        colour_ratio[k1], i0, j0, fi, fj, 2
    )
    return r * alpha, g * alpha, b * alpha, alpha


@njit(nogil=True, cache=True)
def _plane(t, f, ox, oy, oz, dx, dy, dz, planes):
    """(a, b): the ray is inside face f's half-space where a + b t >= 0."""
    a = planes[t, f, 0] * ox + planes[t, f, 1] * oy + planes[t, f, 2] * oz + planes[t, f, 3]
    b = planes[t, f, 0] * dx + planes[t, f, 1] * dy + planes[t, f, 2] * dz
    return a, b


def pack_planes(normals: np.ndarray, anchors: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    """(m, 4, 4) inward unit plane equations (N, D) with N = sigma n / |n| and D = -N . anchor,
    so that a = N . o + D is the signed distance. Both cells of a face get exactly opposite
    equations (negation and |n| are exact under it), so they compute the same crossing
    parameter; one array keeps a cell's planes together in memory, which the walk reads at
    random. Flat cells (n = 0) get zero planes."""
    length = np.linalg.norm(normals, axis=-1)
    inward = normals * (sigma / np.where(length > 0, length, 1.0))[..., None]
    offsets = -np.einsum("mfk,mfk->mf", inward, anchors)
    return np.ascontiguousarray(np.concatenate([inward, offsets[..., None]], axis=-1))


#: |b| (the cosine between the ray and a face plane's normal) at or below this: the ray runs
#: parallel to the plane.
PARALLEL = 1e-12


@njit(nogil=True, cache=True)
def _symbolic_inside(t, f, planes):
    """Whether a ray lying in face f's plane counts as inside the cell: the ray moved by
    (e, e^2, e^3) for an infinitesimal e lies inside iff the first non-zero component of the
    inward normal is positive. Exactly one of the two cells of a face, and one cell around an
    edge, owns such a ray."""
    for k in range(3):
        if planes[t, f, k] != 0.0:
            return planes[t, f, k] > 0.0
    return False


@njit(nogil=True, cache=True)
def _exit(t, ox, oy, oz, dx, dy, dz, planes, on_plane):
    """(t_exit, face) of the ray in tetrahedron t: the first plane it heads out of. A ray lying in
    a face plane that the symbolic perturbation puts outside this cell leaves through that face
    at once (t_exit = -inf): the cell across it owns the ray."""
    t_out = math.inf
    face = -1
    for f in range(4):
        a, b = _plane(t, f, ox, oy, oz, dx, dy, dz, planes)
        if b < -PARALLEL:
            if -a / b < t_out:
                t_out = -a / b
                face = f
        elif b <= PARALLEL and abs(a) <= on_plane and not _symbolic_inside(t, f, planes):
            return -math.inf, f
    return t_out, face


@njit(nogil=True, cache=True)
def _entries(q, rays, cells, boundary, ts, ids, svals):
    """Entries of ray q of the `BinnedRays` rays into the `TetCells` cells through faces marked in
    `boundary`, sorted by t into ts (their ray parameters), ids (their cells) and svals (the
    values there): (count, dropped). A candidate cell is an entry where the ray enters it
    through a boundary face, or starts inside it."""
    ox, oy, oz = rays.origins[q, 0], rays.origins[q, 1], rays.origins[q, 2]
    dx, dy, dz = rays.directions[q, 0], rays.directions[q, 1], rays.directions[q, 2]
    tmax, offsets, cand = rays.far[q], rays.offsets, rays.candidates
    planes, tvals, grads, corner, on_plane = (
        cells.planes,
        cells.values,
        cells.gradients,
        cells.corner,
        cells.on_plane,
    )
    count = 0
    dropped = 0
    for c in range(offsets[q], offsets[q + 1]):
        t = cand[c]
        # The ray enters the mesh where it crosses a boundary face of this cell heading inwards,
        # inside the face's triangle (closed, within on_plane), or it starts inside the cell (the
        # near plane cuts the mesh). The walk starts there even when this cell only touches the
        # ray at an edge or a vertex: it steps on to the cell that owns the ray at no length.
        t0 = -1.0
        inside_at_origin = True
        for f in range(4):
            a, b = _plane(t, f, ox, oy, oz, dx, dy, dz, planes)
            if a < -on_plane:
                inside_at_origin = False
            if not boundary[t, f] or not (b > PARALLEL):
                continue
            t_hit = -a / b
            if not (0.0 <= t_hit <= tmax) or (t0 >= 0.0 and t_hit >= t0):
                continue
            on_triangle = True
            for g in range(4):
                if g != f:
                    ag, bg = _plane(t, g, ox, oy, oz, dx, dy, dz, planes)
                    if ag + bg * t_hit < -on_plane:
                        on_triangle = False
            if on_triangle:
                t0 = t_hit
        if inside_at_origin:
            t0 = 0.0
        if t0 < 0.0:
            continue
        # the linear field at the entry point, from the cell's first vertex and its gradient
        s0 = (
            tvals[t, 0]
            + grads[t, 0] * (ox + t0 * dx - corner[t, 0])
            + grads[t, 1] * (oy + t0 * dy - corner[t, 1])
            + grads[t, 2] * (oz + t0 * dz - corner[t, 2])
        )
        if count == ts.shape[0]:
            dropped += 1
            continue
        k = count  # insertion into the sorted list
        while k > 0 and ts[k - 1] > t0:
            ts[k] = ts[k - 1]
            ids[k] = ids[k - 1]
            svals[k] = svals[k - 1]
            k -= 1
        ts[k] = t0
        ids[k] = t
        svals[k] = s0
        count += 1
    return count, dropped


@njit(nogil=True, parallel=True, cache=True)
def cast_rays(rays, cells, walked, table, tf, options, sp, out, stats):
    """One block of `BinnedRays` rays through the `TetCells` cells, integrated with the
    `SegmentTable` table as the `WalkOptions` options say (the `PackedTF` tf colours cut faces), lit by the `ShadeParams` sp: out (n, 4) premultiplied RGBA (for
    maximum / minimum / average: the value in out[:, 0] and 1 in out[:, 1] where the ray met data);
    stats (n, 4) = cell steps, cells integrated, walks cut at max_steps, entries dropped.

    `WalkedSet` walked: walkable are the cells a walk may run through at positive length (the entry
    faces in `boundary` and the rays' candidates are theirs). A walk steps into any usable cell, so
    that it goes around an edge or a vertex at zero length as always, and ends where it would run
    through a cell outside `walkable`."""
    orig, dirs, tfar, offsets = rays.origins, rays.directions, rays.far, rays.offsets
    neighbors, planes, grads, ok, on_plane = (
        cells.neighbors,
        cells.planes,
        cells.gradients,
        cells.usable,
        cells.on_plane,
    )
    boundary, walkable, visible = walked.boundary, walked.walkable, walked.visible
    mode, termination, max_steps = options.mode, options.termination, options.max_steps
    n = orig.shape[0]
    blocks = (n + RAY_BLOCK - 1) // RAY_BLOCK
    for block in prange(blocks):  # the entry lists are allocated once per block of rays, not per ray
        ts = np.empty(MAX_ENTRIES)
        ids = np.empty(MAX_ENTRIES, np.int64)
        svals = np.empty(MAX_ENTRIES)
        for q in range(block * RAY_BLOCK, min(n, (block + 1) * RAY_BLOCK)):
            for c in range(4):
                out[q, c] = 0.0
                stats[q, c] = 0
            if offsets[q + 1] == offsets[q]:
                continue
            ox, oy, oz = orig[q, 0], orig[q, 1], orig[q, 2]
            dx, dy, dz = dirs[q, 0], dirs[q, 1], dirs[q, 2]
            # the part of the ray the clip region keeps, the far plane included
            keep0, keep1, entering = clip_entry(ox, oy, oz, dx, dy, dz, rays.planes, 0.0, tfar[q])
            if not keep1 > keep0:
                continue
            face_pending = rays.cap and entering >= 0 and mode == COMPOSITE  # a cut face at keep0
            count, dropped = _entries(q, rays, cells, boundary, ts, ids, svals)
            stats[q, 3] = dropped
            if count == 0:
                continue
            hx, hy, hz = headlight_half_vector(sp.lx, sp.ly, sp.lz, dx, dy, dz)
            cr = 0.0
            cg = 0.0
            cb = 0.0
            trans = 1.0
            best = 0.0
            found = False
            integral = 0.0
            total = 0.0
            steps = 0
            integrated = 0
            cut = 0
            t_done = -math.inf
            done = False
            for e in range(count):
                if done:
                    break
                if ts[e] < t_done:
                    continue
                if ts[e] >= keep1:
                    break
                t = ids[e]
                t_in = ts[e]
                s_in = svals[e]
                walked = 0
                while True:
                    t_out, face = _exit(t, ox, oy, oz, dx, dy, dz, planes, on_plane)
                    if face < 0:
                        break
                    if t_out < t_in:
                        t_out = t_in
                    if t_out > keep1:
                        t_out = keep1
                    if t_out > t_in and not walkable[t]:
                        t_out = t_in  # the ray leaves the walked cells here
                        break
                    # the field is linear in the cell: exact along the ray from the entry value
                    slope = grads[t, 0] * dx + grads[t, 1] * dy + grads[t, 2] * dz
                    s_out = s_in + slope * (t_out - t_in)
                    # what the clip region keeps of the segment: cut at keep0 in front
                    t_kept = max(t_in, keep0)
                    s_kept = s_in + slope * (t_kept - t_in) if t_kept > t_in else s_in
                    length = t_out - t_kept
                    steps += 1
                    walked += 1
                    if (
                        face_pending and t_in <= keep0 < t_out
                    ):  # the cell where the ray enters through a plane
                        face_pending = False
                        pn = rays.planes[entering]
                        fr, fg, fb, seen = cut_face(tf, s_kept, pn[0], pn[1], pn[2], sp, dx, dy, dz)
                        if seen:  # opaque: nothing behind it shows
                            cr, cg, cb, trans = fr, fg, fb, 0.0
                            done = True
                            break
                    if length > 0.0:
                        if mode != COMPOSITE:
                            if mode == AVERAGE:
                                integral += 0.5 * (s_kept + s_out) * length
                                total += length
                            else:
                                v = max(s_kept, s_out) if mode == MAXIMUM else min(s_kept, s_out)
                                if (
                                    not found
                                    or (mode == MAXIMUM and v > best)
                                    or (mode == MINIMUM and v < best)
                                ):
                                    best = v
                            found = True
                        elif visible[t]:
                            r, g, b, a = integrate_segment(table, s_kept, s_out, length)
                            if sp.on:
                                diffuse, specular = blinn_phong_factors(
                                    grads[t, 0], grads[t, 1], grads[t, 2], hx, hy, hz, sp
                                )
                                r = min(r * diffuse + specular * a, a)
                                g = min(g * diffuse + specular * a, a)
                                b = min(b * diffuse + specular * a, a)
                            cr += trans * r
                            cg += trans * g
                            cb += trans * b
                            trans *= 1.0 - a
                            integrated += 1
                            if 1.0 - trans >= termination:
                                done = True
                                break
                    if t_out >= keep1:
                        done = True
                        break
                    nb = neighbors[t, face]
                    if nb < 0 or not ok[nb]:
                        break
                    if walked >= max_steps:
                        cut += 1
                        break
                    t = nb
                    t_in = t_out
                    s_in = s_out
                t_done = t_out
            stats[q, 0] = steps
            stats[q, 1] = integrated
            stats[q, 2] = cut
            if mode != COMPOSITE:
                if found:
                    out[q, 0] = integral / total if mode == AVERAGE else best
                    out[q, 1] = 1.0
            else:
                out[q, 0] = cr
                out[q, 1] = cg
                out[q, 2] = cb
                out[q, 3] = 1.0 - trans
