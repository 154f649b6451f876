"""Reference ray integration through a tetrahedral mesh with linear (barycentric) reconstruction.

Why: meshes need the same exact integral as grids, including non-convex boundaries, flat cells and
rays that run exactly through shared faces, edges or vertices.

How:
1. Per volume (`prepare_tets`): for each tetrahedron and each face f (opposite vertex f) the face
   plane is stored as a point p_a and a normal n = (p_b - p_a) x (p_c - p_a), where a < b < c are
   the face's global vertex ids in increasing order, with sigma_f = +-1 so that
   sigma_f n.(x - p_a) >= 0 inside. Because the plane is computed from the sorted ids, the two
   tetrahedra sharing a face hold bit-identical planes with opposite sigma. Flat tetrahedra
   (|6V| <= 1e-12 l_max^3) and those with a non-finite vertex value are dropped: they contribute
   nothing. The constant gradient of the linear field is sum_f v_f sigma_f n_f / D_f with
   D_f = sigma_f n_f.(p_f - p_a) (= 6V).
2. Per frame (`tet_boxes`): vertices are projected with the camera's view and projection
   matrices, giving each tetrahedron the pixel box that holds the centres inside the bounding
   box of its projection. Tetrahedra wholly before the near or beyond the far plane are culled;
   one with a vertex behind the eye gets the whole image. Per block of rows (`bin_rows`), each
   tetrahedron is listed in the pixels of its box (CSR arrays: offsets per pixel, tetrahedron
   ids), so memory follows the block, not the frame.
3. Per pixel ray (`render_tets`): each candidate is clipped against its four face planes in
   float64: with a = sigma n.(o - p_a), b = sigma n.d, a face with b > 0 bounds t from below by
   -a/b, one with b < 0 from above. Both neighbours compute the same -a/b, so the ray is
   partitioned exactly at shared faces. When b == 0 the ray is parallel to the plane and inside
   iff a > 0, or, for a == 0 (the ray lies in the plane), by a symbolic perturbation of the ray
   origin by (eps, eps^2, eps^3): inside iff the first non-zero component of sigma n is positive.
   Exactly one of the cells around a shared face or edge therefore owns a ray lying in it: no
   double counting, no gaps. The value at the entry point comes from the barycentric weights
   lambda_f ~ sigma_f (a_f + b_f t) (normalised by their sum) and the slope ds/dt = grad s . d.
4. The intervals are sorted by entry (stable, so ties keep mesh order), and
   `ray_integral.integrate_ray` integrates them front to back; gaps (outside a non-convex mesh)
   contribute nothing.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from volren.renderers.reference.ray_integral import integrate_ray, store_pixel

#: A tetrahedron with |6V| <= FLAT_TOL * (longest edge)^3 has no volume and is dropped.
FLAT_TOL = 1e-12


@njit(cache=True)
def prepare_tets(points, tets, values):
    """Face planes, signs, vertex values, gradients and a usable flag per tetrahedron."""
    m = tets.shape[0]
    normals = np.zeros((m, 4, 3))
    anchors = np.zeros((m, 4, 3))
    sigma = np.zeros((m, 4))
    tvals = np.zeros((m, 4))
    grads = np.zeros((m, 3))
    ok = np.zeros(m, np.bool_)
    flat = 0
    for t in range(m):
        finite = True
        for f in range(4):
            v = values[tets[t, f]]
            tvals[t, f] = v
            if not math.isfinite(v):
                finite = False
        lmax = 0.0
        for e0 in range(4):
            for e1 in range(e0 + 1, 4):
                p0 = tets[t, e0]
                p1 = tets[t, e1]
                dx = points[p1, 0] - points[p0, 0]
                dy = points[p1, 1] - points[p0, 1]
                dz = points[p1, 2] - points[p0, 2]
                lmax = max(lmax, math.sqrt(dx * dx + dy * dy + dz * dz))
        good = True
        gx = 0.0
        gy = 0.0
        gz = 0.0
        for f in range(4):
            # the three other vertices, sorted by global id
            ia = -1
            ib = -1
            ic = -1
            for g in range(4):
                if g == f:
                    continue
                v = tets[t, g]
                if ia < 0:
                    ia = v
                elif ib < 0:
                    ib = v
                else:
                    ic = v
            if ia > ib:
                ia, ib = ib, ia
            if ib > ic:
                ib, ic = ic, ib
            if ia > ib:
                ia, ib = ib, ia
            ax, ay, az = points[ia, 0], points[ia, 1], points[ia, 2]
            ux = points[ib, 0] - ax
            uy = points[ib, 1] - ay
            uz = points[ib, 2] - az
            vx = points[ic, 0] - ax
            vy = points[ic, 1] - ay
            vz = points[ic, 2] - az
            nx = uy * vz - uz * vy
            ny = uz * vx - ux * vz
            nz = ux * vy - uy * vx
            opp = tets[t, f]
            dvol = nx * (points[opp, 0] - ax) + ny * (points[opp, 1] - ay) + nz * (points[opp, 2] - az)
            if not (abs(dvol) > FLAT_TOL * lmax * lmax * lmax):
                good = False
                break
            sg = 1.0 if dvol > 0.0 else -1.0
            normals[t, f, 0] = nx
            normals[t, f, 1] = ny
            normals[t, f, 2] = nz
            anchors[t, f, 0] = ax
            anchors[t, f, 1] = ay
            anchors[t, f, 2] = az
            sigma[t, f] = sg
            w = tvals[t, f] * sg / (sg * dvol)
            gx += w * nx
            gy += w * ny
            gz += w * nz
        if not good:
            flat += 1
        grads[t, 0] = gx
        grads[t, 1] = gy
        grads[t, 2] = gz
        ok[t] = good and finite
    return normals, anchors, sigma, tvals, grads, ok, flat


def ray_far(camera, dirs: np.ndarray) -> np.ndarray:
    """Distance along each ray from the near plane (where it starts) to the far plane."""
    near, far = camera.clipping_range
    cos = dirs @ np.asarray(camera.direction, dtype=np.float64)
    return (far - near) / cos


def pixel_coordinates(camera, width: int, height: int, points: np.ndarray) -> tuple[np.ndarray, np.ndarray,
                                                                                     np.ndarray]:
    """(px, py, w): points (n, 3) at pixel coordinates (pixel centres at integers, row 0 at the top)
    and their clip w (<= 0: on or behind the eye's plane, where px, py are the points divided by 1)."""
    matrix = camera.projection_matrix(width / height) @ camera.view_matrix()
    n = len(points)
    px, py, w = np.empty(n), np.empty(n), np.empty(n)
    _pixel_coordinates(np.ascontiguousarray(points, dtype=np.float64), matrix, int(width), int(height), px, py, w)
    return px, py, w


@njit(cache=True)
def _pixel_coordinates(points, m, width, height, px, py, pw):
    for i in range(points.shape[0]):
        x, y, z = points[i, 0], points[i, 1], points[i, 2]
        w = m[3, 0] * x + m[3, 1] * y + m[3, 2] * z + m[3, 3]
        pw[i] = w
        if not (w > 0.0):
            w = 1.0
        px[i] = ((m[0, 0] * x + m[0, 1] * y + m[0, 2] * z + m[0, 3]) / w + 1.0) * 0.5 * width - 0.5
        py[i] = (1.0 - (m[1, 0] * x + m[1, 1] * y + m[1, 2] * z + m[1, 3]) / w) * 0.5 * height - 0.5


def projected_boxes(camera, width: int, height: int, points: np.ndarray, tets: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """Pixel boxes of the projected tetrahedra whose `ok` is set (see `tet_boxes`)."""
    px, py, w = pixel_coordinates(camera, width, height, points)
    view = camera.view_matrix()
    depth = -(np.asarray(points, dtype=np.float64) @ view[2, :3] + view[2, 3])
    near, far = camera.clipping_range
    return tet_boxes(px, py, w, np.ascontiguousarray(depth), tets, ok, width, height, near, far)


@njit(cache=True)
def tet_boxes(px, py, pw, depth, tets, ok, width, height, near, far):
    """Pixel bounding box (x0, x1, y0, y1) of every tetrahedron's projection; x0 = -1: none.

    px, py: projected vertex positions in pixel-centre units (pixel (i, j) has its centre at
    (i, j), row 0 at the top); pw: clip w (<= 0 behind the eye); depth: eye-space distance along
    the view direction. Pixel centres within 1e-4 pixel of the box count (rounding margin).
    """
    m = tets.shape[0]
    boxes = np.full((m, 4), -1, np.int64)
    eps = 1e-4
    for t in range(m):
        if not ok[t]:
            continue
        dmin = math.inf
        dmax = -math.inf
        behind = False
        xmin = math.inf
        xmax = -math.inf
        ymin = math.inf
        ymax = -math.inf
        for f in range(4):
            v = tets[t, f]
            dmin = min(dmin, depth[v])
            dmax = max(dmax, depth[v])
            if not (pw[v] > 0.0):
                behind = True
            xmin = min(xmin, px[v])
            xmax = max(xmax, px[v])
            ymin = min(ymin, py[v])
            ymax = max(ymax, py[v])
        if dmax < near or dmin > far:
            continue
        if behind:
            x0, x1, y0, y1 = 0, width - 1, 0, height - 1
        else:
            if not (xmax >= -1.0 and xmin <= width and ymax >= -1.0 and ymin <= height):
                continue
            x0 = max(0, int(math.ceil(xmin - eps)))
            x1 = min(width - 1, int(math.floor(xmax + eps)))
            y0 = max(0, int(math.ceil(ymin - eps)))
            y1 = min(height - 1, int(math.floor(ymax + eps)))
            if x1 < x0 or y1 < y0:
                continue
        boxes[t, 0] = x0
        boxes[t, 1] = x1
        boxes[t, 2] = y0
        boxes[t, 3] = y1
    return boxes


@njit(cache=True)
def bin_rows(boxes, width, row0, row1):
    """CSR lists of candidate tetrahedra for the pixels of rows row0 .. row1 - 1 (row-major,
    pixel index relative to the first pixel of row0): (offsets, tetrahedron ids)."""
    n = (row1 - row0) * width
    counts = np.zeros(n + 1, np.int64)
    m = boxes.shape[0]
    for t in range(m):
        if boxes[t, 0] < 0:
            continue
        y0 = max(boxes[t, 2], row0)
        y1 = min(boxes[t, 3], row1 - 1)
        for y in range(y0, y1 + 1):
            base = (y - row0) * width + 1
            for x in range(boxes[t, 0], boxes[t, 1] + 1):
                counts[base + x] += 1
    offsets = np.cumsum(counts)
    fill = offsets[:-1].copy()
    cand = np.empty(offsets[-1], np.int64)
    for t in range(m):
        if boxes[t, 0] < 0:
            continue
        y0 = max(boxes[t, 2], row0)
        y1 = min(boxes[t, 3], row1 - 1)
        for y in range(y0, y1 + 1):
            base = (y - row0) * width
            for x in range(boxes[t, 0], boxes[t, 1] + 1):
                p = base + x
                cand[fill[p]] = t
                fill[p] += 1
    return offsets, cand


@njit(cache=True)
def clip_tet(t, ox, oy, oz, dx, dy, dz, tmax, normals, anchors, sigma, tvals):
    """(hit, t0, t1, s(t0)) of a ray against tetrahedron t; see the module docstring."""
    tlo = 0.0
    thi = tmax
    for f in range(4):
        nx = normals[t, f, 0]
        ny = normals[t, f, 1]
        nz = normals[t, f, 2]
        sg = sigma[t, f]
        a = nx * (ox - anchors[t, f, 0]) + ny * (oy - anchors[t, f, 1]) + nz * (oz - anchors[t, f, 2])
        b = nx * dx + ny * dy + nz * dz
        a *= sg
        b *= sg
        if b > 0.0:
            tc = -a / b
            if tc > tlo:
                tlo = tc
        elif b < 0.0:
            tc = -a / b
            if tc < thi:
                thi = tc
        else:
            if a < 0.0:
                return False, 0.0, 0.0, 0.0
            if a == 0.0:
                # ray in the face plane: symbolic perturbation of the origin by (e, e^2, e^3)
                if nx != 0.0:
                    first = sg * nx
                elif ny != 0.0:
                    first = sg * ny
                else:
                    first = sg * nz
                if not (first > 0.0):
                    return False, 0.0, 0.0, 0.0
        if not (thi > tlo):
            return False, 0.0, 0.0, 0.0
    # barycentric weights at the entry point (the same a, b as above, recomputed)
    wsum = 0.0
    s = 0.0
    for f in range(4):
        nx = normals[t, f, 0]
        ny = normals[t, f, 1]
        nz = normals[t, f, 2]
        a = nx * (ox - anchors[t, f, 0]) + ny * (oy - anchors[t, f, 1]) + nz * (oz - anchors[t, f, 2])
        b = nx * dx + ny * dy + nz * dz
        w = sigma[t, f] * (a + b * tlo)
        wsum += w
        s += w * tvals[t, f]
    if wsum > 0.0:
        s /= wsum
    else:
        s = 0.25 * (tvals[t, 0] + tvals[t, 1] + tvals[t, 2] + tvals[t, 3])
    return True, tlo, thi, s


@njit(parallel=True, cache=True)
def render_tets(
    orig, dirs, tfar, offsets, cand, normals, anchors, sigma, tvals, grads,
    tf, spar, mode, h0, tol, max_levels, out, stats,
):  # fmt: skip
    """One block of n rays with their CSR candidate lists: out (n, 4) RGBA; stats (n, 5) =
    samples, level, unconverged, subdivision cap hits, intervals."""
    n = orig.shape[0]
    shading = spar[0]
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
        t0s = np.empty(k)
        t1s = np.empty(k)
        s0s = np.empty(k)
        ids = np.empty(k, np.int64)
        m = 0
        for c in range(k):
            t = cand[c0 + c]
            hit, t0, t1, s0 = clip_tet(t, ox, oy, oz, dx, dy, dz, tfar[q], normals, anchors, sigma, tvals)
            if hit:
                t0s[m] = t0
                t1s[m] = t1
                s0s[m] = s0
                ids[m] = t
                m += 1
        if m == 0:
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
        result = integrate_ray(ta, tb, P, G, m, mode, h0, tol, max_levels, tf, spar, dx, dy, dz)
        store_pixel(out, stats, q, result, m)
