"""A ray clipped against one tetrahedron's face planes, exactly at shared faces.

Why: rays must be partitioned at the faces two cells share, with no gap and no double count, even
when they run exactly through faces, edges or vertices (the reference renderer and picking).

The planes are those of `volren.model.tet_mesh.FacePlanes`: face f of cell t is sigma n.(x - p_a)
>= 0 inside, with n and p_a from the face's vertices sorted by global id, so the two cells of a
face hold bit-identical planes with opposite sigma. With a = sigma n.(o - p_a) and b = sigma n.d,
a face with b > 0 bounds t from below by -a/b, one with b < 0 from above; both neighbours compute
the same -a/b. When b == 0 the ray is parallel to the plane and inside iff a > 0, or, for a == 0
(the ray lies in the plane), by a symbolic perturbation of the origin by (eps, eps^2, eps^3):
inside iff the first non-zero component of sigma n is positive, so exactly one of the cells
around a face or edge owns a ray lying in it. The value at the entry comes from the barycentric
weights lambda_f ~ sigma_f (a_f + b_f t), normalised by their sum.
"""

from __future__ import annotations

from numba import njit


@njit(nogil=True, cache=True)
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
