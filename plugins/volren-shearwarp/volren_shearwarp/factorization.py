"""The shear-warp factorization of a view (Lacroute and Levoy 1994) in voxel-index space.

Why: compositing is fast when every slice of the volume maps onto the intermediate image by a
scale and a translation per slice (no 3D resampling), and the final image is one 2D warp. Doing
the factorization in voxel-index coordinates makes anisotropic spacing free: the shear is the
ray's slope in index units, which stays at most 1 along the principal axis.

Conventions (all exact, derived from the camera's position and direction, the same numbers that
`Camera.view_matrix` / `projection_matrix` are built from):
- The principal axis c is the index axis that the rays cross slice by slice; a and b are the
  other two (a varies fastest in the slice copies of `classified`). Permutations `PERMS[c]`
  give (a, b, c) as volume axes (0 = x, 1 = y, 2 = z).
- The intermediate image lies in the plane of the front slice c0. Its pixel (p, q) is centred at
  in-plane index coordinates (A0 + p h, B0 + q h), h = 1 / scale voxels per pixel, with A0, B0
  integers, so with scale 1 intermediate pixels sit on lattice columns.
- The ray through intermediate pixel (p, q) crosses the plane c = k at
  a = alpha_a[k] + beta_a[k] p and b = alpha_b[k] + beta_b[k] q: a translation per slice for a
  parallel camera (beta = h), a scale and translation under perspective (all rays through the
  eye). Both are linear in p and in q separately, which is what lets scanlines stay scanlines.
- The warp sends each output pixel's ray (DESIGN.md: NDC ((i + .5) / w * 2 - 1, 1 - (j + .5) /
  h * 2), row 0 at the top) through the camera's inverse view-projection matrix to the plane c0:
  affine for parallel projection, projective under perspective, exact either way.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import NDArray

from volren.errors import VolrenError
from volren.model import Camera, UniformVolume

#: (a, b, c) volume axes for each principal axis c (x = 0, y = 1, z = 2).
PERMS: dict[int, tuple[int, int, int]] = {0: (1, 2, 0), 1: (0, 2, 1), 2: (0, 1, 2)}
#: Largest intermediate image side; beyond it the oversampling is reduced.
MAX_INTERMEDIATE_SIDE = 8192
#: An eye closer than this (index units) to a face plane of the principal axis is on it.
EYE_EPS = 1e-6


@dataclass(frozen=True)
class Factorization:
    """Everything the compositing and warp kernels need about one view."""

    axis: int  #: principal axis c (0, 1, 2 = x, y, z)
    perm: tuple[int, int, int]  #: volume axes of (a, b, c)
    order: NDArray[np.int64]  #: voxel slice indices k, front to back
    alpha_a: NDArray[np.float64]  #: per slice k (indexed by k): a = alpha_a[k] + beta_a[k] p
    beta_a: NDArray[np.float64]
    alpha_b: NDArray[np.float64]
    beta_b: NDArray[np.float64]
    width: int  #: intermediate image size in pixels
    height: int
    scale: float  #: intermediate pixels per voxel
    origin_ab: tuple[float, float]  #: (A0, B0): in-plane coordinates of intermediate pixel (0, 0)
    plane: float  #: c0, the index of the front slice (the intermediate image's plane)
    perspective: bool
    eye: NDArray[np.float64]  #: eye (perspective) in index coordinates (a, b, c), else zeros
    direction: NDArray[np.float64]  #: unit view direction in permuted world components (a, b, c)
    spacing: NDArray[np.float64]  #: spacing of (a, b, c)
    max_shear: float  #: largest |da/dc|, |db/dc| of any ray through the volume (index units)
    slab_length: float  #: world length between two slices along a ray (parallel), else 0
    warp: WarpMap  #: output pixel -> intermediate plane, for the final warp (made once per view)

    def length_terms(self) -> tuple[NDArray[np.float64], NDArray[np.float64], float, float]:
        """(col_d2, row_d2, dc2, inv_norm): under perspective the slice-to-slice length of the ray
        through pixel (q, p) is sqrt(col_d2[p] + row_d2[q] + dc2) * inv_norm (see `pixel_lengths`),
        separable so that kernels need not hold a per-pixel array."""
        a0, b0 = self.origin_ab
        h = 1.0 / self.scale
        da = (a0 + h * np.arange(self.width) - self.eye[0]) * self.spacing[0]
        db = (b0 + h * np.arange(self.height) - self.eye[1]) * self.spacing[1]
        dc = (self.plane - self.eye[2]) * self.spacing[2]
        return da**2, db**2, float(dc**2), 1.0 / abs(self.plane - self.eye[2])

    def pixel_lengths(self) -> NDArray[np.float64]:
        """(height, width) world length of one slice-to-slice step along each intermediate ray.

        Under perspective every ray through the eye crosses consecutive slices at points that
        differ by (P0 - E) / (c0 - E_c), P0 the pixel's point on the plane: the length is fixed
        per pixel and the same for every slab, so tables are looked up by pixel."""
        if not self.perspective:
            return np.full((self.height, self.width), self.slab_length)
        col_d2, row_d2, dc2, inv_norm = self.length_terms()
        return np.sqrt(col_d2[None, :] + row_d2[:, None] + dc2) * inv_norm

    def clip_limits(self, camera: Camera, volume: UniformVolume) -> tuple[NDArray, NDArray] | None:
        """Where each intermediate ray lies between the camera's near and far planes: (lo, hi), each
        (height, width), an interval of u = |c - c0| (slices behind the front slice; slab m of the
        compositing order spans u in [m - 1, m]); None when neither plane cuts the volume's box, so
        that every ray is whole (the common case: cameras from `Camera.orbit` or
        `reset_clipping_range`).

        Why linear in u: the planes are at fixed depths (distance from the eye along the view
        direction, vtkCamera's clipping range), and along a ray the depth is linear in c. With D0
        the depth of the ray's point on the plane c0: a parallel ray runs along the view direction,
        so depth = D0 + u * slab_length; a perspective ray through the eye E has depth
        f(c) D0 with f = (c - E_c) / (c0 - E_c) = 1 + u / |c0 - E_c|. A perspective ray whose
        point on the plane is not ahead of the eye (D0 <= 0) is empty."""
        near, far = camera.clipping_range
        bounds = volume.bounds
        corners = np.array(
            [[x, y, z] for x in bounds[0:2] for y in bounds[2:4] for z in bounds[4:6]], np.float64
        )
        view = np.asarray(camera.direction, np.float64)
        depth = (corners - np.asarray(camera.position, np.float64)) @ view
        if near <= depth.min() and far >= depth.max():
            return None
        perm = list(self.perm)
        # depth of plane point (A0 + h p, B0 + h q, c0) in index units: separable in p and q
        rel = (np.asarray(volume.origin, np.float64) - np.asarray(camera.position, np.float64))[perm]
        a0, b0 = self.origin_ab
        h = 1.0 / self.scale
        d = self.direction
        col = (rel[0] + (a0 + h * np.arange(self.width)) * self.spacing[0]) * d[0]
        row = (rel[1] + (b0 + h * np.arange(self.height)) * self.spacing[1]) * d[1]
        d0 = row[:, None] + col[None, :] + (rel[2] + self.plane * self.spacing[2]) * d[2]
        if self.perspective:
            rate = d0 / abs(self.plane - self.eye[2])
        else:
            rate = np.full_like(d0, self.slab_length)
        ahead = rate > 0.0
        safe = np.where(ahead, rate, 1.0)
        lo = np.where(ahead, (near - d0) / safe, np.inf)
        hi = np.where(ahead, (far - d0) / safe, -np.inf)
        return np.ascontiguousarray(lo), np.ascontiguousarray(hi)

    def region_limits(self, half_spaces: NDArray[np.float64]) -> tuple[NDArray, NDArray]:
        """Where each intermediate ray lies on the kept side of every half-space row (a, b, c, d) of
        `half_spaces` ((m, 4), grid-index x, y, z: `ClipRegion.half_spaces_in_grid`): (lo, hi), each
        (height, width), an interval of u = |c - c0| as `clip_limits`' (empty where lo >= hi).

        Why an interval: a ray is a straight line in index space and u is linear along it (it crosses
        slice k at (alpha_a[k] + beta_a[k] p, alpha_b[k] + beta_b[k] q, k), under perspective too), so
        a x + b y + c z + d is linear in u; its values on the front and back slices give the crossing
        exactly, and the kept region, an intersection of half-spaces, is convex (Real-Time Volume
        Graphics, section 15.1). A ray parallel to a plane is kept whole or lost whole."""
        lo = np.full((self.height, self.width), -np.inf)
        hi = np.full((self.height, self.width), np.inf)
        k0, k1 = int(self.order[0]), int(self.order[-1])
        for row in np.asarray(half_spaces, np.float64).reshape(-1, 4):
            # a x + b y + c z + d where the ray crosses slice k: affine in the pixel's column and row
            ra, rb, rc = row[list(self.perm)]
            front = (ra * self.alpha_a[k0] + rb * self.alpha_b[k0] + rc * k0 + row[3],
                     ra * self.beta_a[k0], rb * self.beta_b[k0])  # fmt: skip
            back = (ra * self.alpha_a[k1] + rb * self.alpha_b[k1] + rc * k1 + row[3],
                    ra * self.beta_a[k1], rb * self.beta_b[k1])  # fmt: skip
            _narrow_to_half_space(
                lo, hi, front, back, float(abs(k0 - self.plane)), float(abs(k1 - self.plane))
            )
        return lo, hi


@njit(nogil=True, cache=True, error_model="numpy")
def _narrow_to_half_space(lo: NDArray, hi: NDArray, front: tuple[float, float, float],
                          back: tuple[float, float, float], u0: float, u1: float) -> None:  # fmt: skip
    """Narrows each intermediate ray's interval of u, (lo, hi) in place, to the side of one plane
    where its value is positive; `front` and `back` give that value on the first and last slice of
    the compositing order (at u0 and u1) as (constant, per column, per row)."""
    for q in range(lo.shape[0]):
        for p in range(lo.shape[1]):
            f0 = front[0] + front[1] * p + front[2] * q
            f1 = back[0] + back[1] * p + back[2] * q
            rate = (f1 - f0) / (u1 - u0) if u1 != u0 else 0.0
            if rate > 0.0:
                lo[q, p] = max(lo[q, p], u0 - f0 / rate)
            elif rate < 0.0:
                hi[q, p] = min(hi[q, p], u0 - f0 / rate)
            elif f0 < 0.0:  # parallel to the plane and on its cut side: lost whole
                lo[q, p] = np.inf
                hi[q, p] = -np.inf


def index_frame(volume: UniformVolume) -> tuple[NDArray, NDArray, NDArray]:
    """(origin, spacing, dims as floats) in x, y, z order."""
    return (np.asarray(volume.origin, np.float64), np.asarray(volume.spacing, np.float64),
            np.asarray(volume.dimensions, np.float64))  # fmt: skip


def _corners(dims: NDArray) -> NDArray:
    n = dims - 1.0
    return np.array([[x, y, z] for x in (0, n[0]) for y in (0, n[1]) for z in (0, n[2])])


def choose_axis(camera: Camera, volume: UniformVolume) -> tuple[int, float]:
    """The principal axis and its largest shear, or a one-line VolrenError when no axis has every
    ray cross its slices in one direction (the eye inside the volume's bounds, under perspective)."""
    origin, spacing, dims = index_frame(volume)
    if camera.parallel:
        d = np.asarray(camera.direction) / spacing
        c = int(np.argmax(np.abs(d)))
        others = [i for i in range(3) if i != c]
        return c, float(max(abs(d[i]) for i in others) / abs(d[c]))
    eye = (np.asarray(camera.position) - origin) / spacing
    best: tuple[float, int] | None = None
    corners = _corners(dims)
    for c in range(3):
        if -EYE_EPS <= eye[c] <= dims[c] - 1 + EYE_EPS:
            continue
        rel = corners - eye
        others = [i for i in range(3) if i != c]
        shear = float(np.max(np.abs(rel[:, others]) / np.abs(rel[:, c : c + 1])))
        if best is None or shear < best[0]:
            best = (shear, c)
    if best is None:
        raise VolrenError(
            "renderer shearwarp cannot render with the eye inside the volume's bounds under perspective "
            "(every slice axis has slices on both sides of the eye): move the camera out or use a parallel projection"
        )
    return best[1], best[0]


def factorize(camera: Camera, volume: UniformVolume, width: int, height: int, oversampling: float,
              max_scale: float = 64.0, min_scale: float = 1.0) -> Factorization:  # fmt: skip
    """The factorization of `camera`'s view of `volume` for a width x height output image, with
    about `oversampling` intermediate pixels per output pixel and at least `min_scale` per voxel
    (1: every voxel resolved; below 1 a draft that samples each slice more coarsely than its lattice)."""
    origin, spacing, dims = index_frame(volume)
    c, max_shear = choose_axis(camera, volume)
    perm = PERMS[c]
    sp = spacing[list(perm)]
    n_c = int(dims[c])
    view_dir = np.asarray(camera.direction, np.float64)
    direction = view_dir[list(perm)]
    perspective = not camera.parallel
    if perspective:
        eye = ((np.asarray(camera.position) - origin) / spacing)[list(perm)]
        forward = eye[2] < 0
    else:
        eye = np.zeros(3)
        d_idx = (view_dir / spacing)[list(perm)]
        forward = d_idx[2] > 0
    order = np.arange(n_c) if forward else np.arange(n_c - 1, -1, -1)
    plane = float(order[0])
    ks = np.arange(n_c, dtype=np.float64)

    # where each slice's lattice projects on the plane c0 (per slice: a = f_k a_plane + g_k)
    if perspective:
        f = (ks - eye[2]) / (plane - eye[2])  # >= 1 behind the front slice
        shift_a, shift_b = eye[0] * (1 - f), eye[1] * (1 - f)
    else:
        f = np.ones(n_c)
        sa, sb = d_idx[0] / d_idx[2], d_idx[1] / d_idx[2]
        shift_a, shift_b = (ks - plane) * sa, (ks - plane) * sb

    # the volume's footprint on the plane: its corners carried back along their rays
    na, nb = dims[perm[0]], dims[perm[1]]
    corner_a, corner_b, corner_k = [], [], []
    for a in (0.0, na - 1):
        for b in (0.0, nb - 1):
            for k in (0, n_c - 1):
                corner_a.append((a - shift_a[k]) / f[k])
                corner_b.append((b - shift_b[k]) / f[k])
                corner_k.append(k)
    a_lo, a_hi, b_lo, b_hi = min(corner_a), max(corner_a), min(corner_b), max(corner_b)

    # the output pixels' rays on the plane: their extent clips the footprint, their density sets the scale
    warp = WarpMap.build(camera, volume, perm, plane, width, height)
    scale = min_scale
    probe = warp.plane_points(np.array([width / 2 - 0.5, width / 2 + 0.5, width / 2 - 0.5]),
                              np.array([height / 2 - 0.5, height / 2 - 0.5, height / 2 + 0.5]))  # fmt: skip
    if probe is not None:
        pa, pb = probe
        step = min(math.hypot(pa[1] - pa[0], pb[1] - pb[0]), math.hypot(pa[2] - pa[0], pb[2] - pb[0]))
        if step > 0 and math.isfinite(step):
            scale = max(min_scale, oversampling / step)
    edges = warp.plane_points(np.array([-0.5, width - 0.5, -0.5, width - 0.5]),
                              np.array([-0.5, -0.5, height - 0.5, height - 0.5]))  # fmt: skip
    if edges is not None:  # every corner ray reaches the plane: the view's footprint is a quadrilateral
        margin = 2.0 / scale + 1.0  # the warp's bilinear footprint, and a voxel to spare
        ea, eb = edges
        a_lo, a_hi = max(a_lo, ea.min() - margin), min(a_hi, ea.max() + margin)
        b_lo, b_hi = max(b_lo, eb.min() - margin), min(b_hi, eb.max() + margin)
    if a_hi < a_lo or b_hi < b_lo:  # the volume is outside the view
        a_lo = a_hi = b_lo = b_hi = 0.0
    scale = min(scale, max_scale, MAX_INTERMEDIATE_SIDE / max(a_hi - a_lo + 3, b_hi - b_lo + 3))
    scale = max(scale, 1e-3)
    h = 1.0 / scale
    a0, b0 = math.floor(a_lo), math.floor(b_lo)
    iw = int(math.floor((a_hi - a0) / h)) + 2
    ih = int(math.floor((b_hi - b0) / h)) + 2

    if perspective:
        slab = 0.0
    else:
        slab = float(np.linalg.norm(np.array([sa, sb, 1.0]) * sp))
    return Factorization(
        axis=c, perm=perm, order=order.astype(np.int64),
        alpha_a=np.ascontiguousarray(f * a0 + shift_a), beta_a=np.ascontiguousarray(f * h),
        alpha_b=np.ascontiguousarray(f * b0 + shift_b), beta_b=np.ascontiguousarray(f * h),
        width=iw, height=ih, scale=scale, origin_ab=(float(a0), float(b0)), plane=plane,
        perspective=perspective, eye=eye, direction=direction, spacing=sp, max_shear=max_shear,
        slab_length=slab, warp=warp,
    )  # fmt: skip


@dataclass(frozen=True)
class WarpMap:
    """Output pixel -> point on the intermediate plane c = c0, in in-plane index coordinates.

    A pixel's ray is the camera's: the inverse view-projection matrix maps its NDC point at depths
    -1 and 1 to world points (as `Camera.pixel_rays` does), here carried on into index coordinates
    of (a, b, c). Because every step is a matrix, the map from (x_ndc, y_ndc, 1) to homogeneous
    plane coordinates is one 3x3 matrix `homography` (affine for a parallel camera)."""

    homography: NDArray[np.float64]  #: (3, 3): [a w, b w, w] = H @ [x_ndc, y_ndc, 1]
    width: int
    height: int
    #: +1 or -1: the sign w must have for the plane point to lie ahead of the camera
    sign: float

    @classmethod
    def build(cls, camera: Camera, volume: UniformVolume, perm: tuple[int, int, int], plane: float,
              width: int, height: int) -> WarpMap:  # fmt: skip
        origin, spacing, _ = index_frame(volume)
        inv = np.linalg.inv(camera.projection_matrix(width / height) @ camera.view_matrix())
        # world (homogeneous) -> permuted index (homogeneous)
        to_index = np.zeros((4, 4))
        for row, axis in enumerate(perm):
            to_index[row, axis] = 1.0 / spacing[axis]
            to_index[row, 3] = -origin[axis] / spacing[axis]
        to_index[3, 3] = 1.0
        m = to_index @ inv  # clip -> permuted index, homogeneous
        # a point on the ray: X(z) = m @ [x, y, z, 1]; solve X_c(z) / X_w(z) = c0 for z (linear)
        # X(z) = U + z V with U = m[:, [0,1,3]] @ [x, y, 1], V = m[:, 2]
        # (U_c - c0 U_w) + z (V_c - c0 V_w) = 0  ->  z = -(U_c - c0 U_w) / (V_c - c0 V_w)
        # plane point homogeneous: X = U (V_c - c0 V_w) - V (U_c - c0 U_w): linear in [x, y, 1]
        mu = m[:, [0, 1, 3]]  # U = mu @ [x, y, 1]
        v = m[:, 2]
        k = v[2] - plane * v[3]
        g = mu[2] - plane * mu[3]  # U_c - c0 U_w = g @ [x, y, 1]
        full = mu * k - np.outer(v, g)  # (4, 3): homogeneous plane point as a function of [x, y, 1]
        homography = full[[0, 1, 3]]
        # which sign of w means "ahead of the camera": the point at depth z is ahead when z > -1
        # (beyond the near plane); z = -g.[x,y,1] / k, X = full @ [x,y,1] / k... decided per pixel
        sign = 1.0 if k > 0 else -1.0
        return cls(homography, width, height, sign)

    def plane_points(self, px: NDArray, py: NDArray) -> tuple[NDArray, NDArray] | None:
        """In-plane (a, b) of the rays through pixel centres (px, py), or None when one misses the plane."""
        x = (px + 0.5) / self.width * 2 - 1
        y = 1 - (py + 0.5) / self.height * 2
        hom = self.homography @ np.stack([x, y, np.ones_like(x)])
        w = hom[2] * self.sign
        if not np.all(w > 1e-300):
            return None
        return hom[0] / hom[2], hom[1] / hom[2]
