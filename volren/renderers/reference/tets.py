"""Reference ray integration through a tetrahedral mesh with linear (barycentric) reconstruction.

Why: meshes need the same exact integral as grids, including non-convex boundaries, flat cells and
rays that run exactly through shared faces, edges or vertices.

How:
1. Per volume, `volren.model.tet_mesh.prepare_mesh` gives each tetrahedron its face planes
   (`FacePlanes`: bit-identical on both sides of a shared face), its vertex values, the constant
   gradient of the linear field and whether it is usable (neither flat nor with a non-finite
   vertex value: unusable cells contribute nothing).
2. Per frame, `volren.kernels.tet_projection` gives every usable tetrahedron its pixel box and,
   per block of rows, the candidate tetrahedra of every pixel.
3. Per pixel ray (`render_tets`), each candidate is clipped against its four face planes in
   float64 (`volren.kernels.tet_clipping.clip_tet`: the ray is partitioned exactly at shared
   faces, and exactly one cell owns a ray lying in a face), giving an interval with the value at
   its entry and the slope ds/dt = grad s . d, cut to the part of the ray the clip region keeps
   (the field is linear in the cell, so the value at a cut is exact).
4. The intervals are sorted by entry (stable, so ties keep mesh order), and
   `refinement.integrate_ray` integrates them front to back; gaps (outside a non-convex mesh)
   contribute nothing.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from volren.kernels.clip_planes import clip_entry
from volren.kernels.cut_faces import cut_face
from volren.kernels.tet_clipping import clip_tet
from volren.renderers.reference.ray_inputs import RayIntervals
from volren.renderers.reference.ray_integral import store_pixel
from volren.renderers.reference.refinement import integrate_ray


@njit(nogil=True, parallel=True, cache=True)
def render_tets(rays, cells, tf, spar, quad, out, stats):
    """One block of n `BinnedRays` rays with their CSR candidate lists through the `CellPlanes`
    cells, integrated as the `Quadrature` quad says with the `ShadeParams` spar: out (n, 4) RGBA;
    stats (n, 5) = samples, level, unconverged, subdivision cap hits, intervals."""
    orig, dirs, tfar, offsets, cand = rays.origins, rays.directions, rays.far, rays.offsets, rays.candidates
    normals, anchors, sigma, tvals, grads = (
        cells.normals,
        cells.anchors,
        cells.sigma,
        cells.values,
        cells.gradients,
    )
    n = orig.shape[0]
    shading = spar.on
    for q in prange(n):
        for c in range(4):
            out[q, c] = 0.0
        for c in range(5):
            stats[q, c] = 0
        c0 = offsets[q]
        k = offsets[q + 1] - c0
        if k == 0:
            continue
        ox, oy, oz = orig[q, 0], orig[q, 1], orig[q, 2]
        dx, dy, dz = dirs[q, 0], dirs[q, 1], dirs[q, 2]
        keep0, keep1, entering = clip_entry(ox, oy, oz, dx, dy, dz, rays.planes, 0.0, tfar[q])
        if not keep1 > keep0:
            continue
        face_value = np.nan  # the value where the ray enters through a plane, inside a cell
        t0s = np.empty(k)
        t1s = np.empty(k)
        s0s = np.empty(k)
        ids = np.empty(k, np.int64)
        m = 0
        for c in range(k):
            t = cand[c0 + c]
            hit, t0, t1, s0 = clip_tet(t, ox, oy, oz, dx, dy, dz, tfar[q], normals, anchors, sigma, tvals)
            if hit and t1 > keep0 and t0 < keep1:  # the cell's interval cut to the kept one
                if t0 <= keep0:
                    s0 += (grads[t, 0] * dx + grads[t, 1] * dy + grads[t, 2] * dz) * (keep0 - t0)
                    t0 = keep0
                    face_value = s0
                t1 = min(t1, keep1)
                t0s[m] = t0
                t1s[m] = t1
                s0s[m] = s0
                ids[m] = t
                m += 1
        if m == 0:
            continue
        if rays.cap and entering >= 0:  # an opaque cut face first
            n = rays.planes[entering]
            r, g, b, visible = cut_face(tf, face_value, n[0], n[1], n[2], spar, dx, dy, dz)
            if visible:
                out[q, 0], out[q, 1], out[q, 2], out[q, 3] = r, g, b, 1.0
                stats[q, 4] = m
                continue
        order = np.argsort(t0s[:m], kind="mergesort")
        ta = np.empty(m)
        tb = np.empty(m)
        P = np.zeros((m, 4))
        G = np.zeros((m if shading else 0, 3, 4))
        for e in range(m):
            j = order[e]
            t = ids[j]
            ta[e] = t0s[j]
            tb[e] = t1s[j]
            P[e, 0] = s0s[j]
            P[e, 1] = grads[t, 0] * dx + grads[t, 1] * dy + grads[t, 2] * dz
            if shading:
                G[e, 0, 0] = grads[t, 0]
                G[e, 1, 0] = grads[t, 1]
                G[e, 2, 0] = grads[t, 2]
        result = integrate_ray(RayIntervals(ta, tb, P, G, m), quad, tf, None, spar, dx, dy, dz)
        store_pixel(out, stats, q, result, m)
