"""The reference renderer against independent closed forms (numpy), and its invariants.

The oracles here never call the renderer's own integration code: slab lengths, optical depths and
emission integrals are computed in numpy from the formulas of DESIGN.md's optical model (the slab
lengths and the linear-colour emission are the conformance kit's, `volren.testing.oracles`).
"""

from __future__ import annotations

import itertools
import json
import math
from pathlib import Path

import numpy as np
import pytest

from tests.session_policy import SHARED_MISSING
from volren.errors import VolrenError, VolrenWarning
from volren.model import BlendMode, Camera, RenderSettings, TetVolume, TransferFunction1D, UniformVolume
from volren.renderers.reference import ReferenceRenderer
from volren.testing.oracles import box_path_lengths, linear_colour_emission
from volren.testing.scenes import kuhn_tetrahedra, lattice_points, positively_oriented

SHARED = Path(__file__).resolve().parents[3] / "shared"
MAXA = 1.0 - 1e-6


# ---------------------------------------------------------------------------------- helpers
def render(volume, tf, camera, width, height=None, **settings):
    r = ReferenceRenderer()
    r.set_volume(volume)
    r.set_transfer_function(tf)
    r.set_settings(RenderSettings(**settings))
    img = r.render(camera, width, height or width)
    assert img.dtype == np.float32 and img.shape == ((height or width), width, 4)
    return r.last_rgba64, r


def grid(values_fn, dims, spacing, origin=(0.0, 0.0, 0.0)):
    """UniformVolume with values_fn(x, y, z) at the grid points."""
    nx, ny, nz = dims
    k, j, i = np.meshgrid(np.arange(nz), np.arange(ny), np.arange(nx), indexing="ij")
    x = origin[0] + i * spacing[0]
    y = origin[1] + j * spacing[1]
    z = origin[2] + k * spacing[2]
    return UniformVolume(values_fn(x, y, z).astype(np.float64), spacing=spacing, origin=origin)


def lattice_tets(dims, spacing, kind=6, skip=()):
    """Points of a lattice and its cubes (less the (i, j, k) in `skip`) split into 6 (Kuhn, as the
    conformance kit's scenes) or 5 (alternating) tetrahedra, positively oriented."""
    nx, ny, nz = dims
    pts = lattice_points(dims, spacing, (0.0, 0.0, 0.0))
    cubes = list(itertools.product(range(nz - 1), range(ny - 1), range(nx - 1)))
    if kind == 6:
        keep = [(ii, jj, kk) not in skip for kk, jj, ii in cubes]
        return pts, positively_oriented(pts, kuhn_tetrahedra(dims).reshape(-1, 6, 4)[keep].reshape(-1, 4))
    tets = []
    for kk, jj, ii in cubes:
        if (ii, jj, kk) in skip:
            continue
        c = {
            (a, b, e): ((kk + e) * ny + jj + b) * nx + ii + a for a in (0, 1) for b in (0, 1) for e in (0, 1)
        }
        even = [(0, 0, 0), (1, 1, 0), (1, 0, 1), (0, 1, 1)]
        odd = [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 1)]
        centre, corners = (odd, even) if (ii + jj + kk) % 2 == 0 else (even, odd)
        tets.append([c[x] for x in centre])
        for cc in corners:
            near = [x for x in centre if sum(abs(a - b) for a, b in zip(x, cc)) == 1]
            tets.append([c[cc]] + [c[x] for x in near])
    return pts, positively_oriented(pts, np.array(tets))


def axis_camera(bounds, axis_from, scale, view_up):
    """Parallel camera looking along an axis through the box centre, from the side `axis_from`."""
    b = np.asarray(bounds, float)
    centre = (b[0::2] + b[1::2]) / 2
    pos = centre + 10.0 * np.asarray(axis_from, float)
    return Camera(position=pos, focal_point=centre, view_up=view_up, parallel=True, parallel_scale=scale,
                  clipping_range=(1.0, 100.0))  # fmt: skip


def grid_camera(n_x, n_y, s, z_top):
    """Parallel camera along -z whose n_x x n_y pixel centres sit on the points (i s, j s)."""
    centre = ((n_x - 1) * s / 2, (n_y - 1) * s / 2, z_top + 10.0)
    return Camera(position=centre, focal_point=(centre[0], centre[1], 0.0), parallel=True,
                  parallel_scale=n_y * s / 2, clipping_range=(1.0, 100.0))  # fmt: skip


def optical_depth_linear_opacity(a_pts, x0, x1):
    """Integral of -ln(1 - a(s)) over s in [x0, x1], a piecewise linear through a_pts (< 1)."""
    xs = np.asarray([p[0] for p in a_pts], float)
    aa = np.asarray([p[1] for p in a_pts], float)
    knots = np.unique(np.clip(np.concatenate([xs, [x0, x1]]), x0, x1))

    def antiderivative(w):  # d/dw of (w ln w - w) is ln w
        return w * math.log(w) - w

    total = 0.0
    for a, b in zip(knots[:-1], knots[1:]):
        wa = 1 - np.interp(a, xs, aa)
        wb = 1 - np.interp(b, xs, aa)
        if abs(wb - wa) < 1e-14:
            total += -(b - a) * math.log(wa)
        else:  # s -> w is linear: ds = (b - a) / (wb - wa) dw
            total += -(b - a) / (wb - wa) * (antiderivative(wb) - antiderivative(wa))
    return total


# ------------------------------------------------------------------------- homogeneous box
@pytest.mark.parametrize("parallel", [False, True])
def test_homogeneous_box_matches_slab_lengths(parallel):
    vol = UniformVolume(np.full((4, 6, 5), 7.0), spacing=(0.7, 1.3, 0.4), origin=(-1.0, 2.0, 0.5))
    a, d, c = 0.35, 0.8, np.array([0.9, 0.4, 0.2])
    tf = TransferFunction1D.constant(a, c, opacity_unit_distance=d)
    cam = Camera.orbit(vol.bounds, 30, 20, zoom=1.3, parallel=parallel)
    rgba, r = render(vol, tf, cam, 24, 20)
    L = box_path_lengths(cam, 24, 20, vol.bounds)
    alpha = 1 - (1 - a) ** (L / d)
    assert (L == 0).any() and (L > 0).any()
    np.testing.assert_allclose(rgba[..., 3], alpha, atol=1e-9, rtol=0)
    np.testing.assert_allclose(rgba[..., :3], alpha[..., None] * c, atol=1e-9, rtol=0)
    assert np.all(rgba[L == 0] == 0)  # rays missing the box give exactly 0
    assert r.last_frame.counters["unconverged_rays"] == 0


def test_homogeneous_box_camera_inside():
    vol = UniformVolume(np.full((5, 5, 5), 1.0), spacing=(1.0, 0.5, 2.0))
    tf = TransferFunction1D.constant(0.2, (1.0, 1.0, 1.0), opacity_unit_distance=1.5)
    cam = Camera(position=(2.0, 1.0, 4.0), focal_point=(2.0, 1.0, 0.0), clipping_range=(0.1, 50.0)).azimuth(
        20
    )
    rgba, _ = render(vol, tf, cam, 16)
    L = box_path_lengths(cam, 16, 16, vol.bounds)
    np.testing.assert_allclose(rgba[..., 3], 1 - 0.8 ** (L / 1.5), atol=1e-9, rtol=0)


@pytest.mark.parametrize("inside", [False, True], ids=["outside", "camera-inside"])
def test_homogeneous_tet_box_no_double_counting(inside):
    """Oblique rays through a tetrahedralized box cross every shared face exactly once."""
    pts, tets = lattice_tets((3, 4, 3), (1.0, 0.6, 1.4))
    vol = TetVolume(pts, tets, np.full(len(pts), 2.0))
    tf = TransferFunction1D.constant(0.4, (0.3, 0.6, 0.9), opacity_unit_distance=0.7)
    if inside:
        cam = Camera(position=(1.0, 0.9, 1.5), focal_point=(1.0, 0.9, 0.0), clipping_range=(0.1, 50.0))
        cam = cam.azimuth(25).elevation(10)
    else:
        cam = Camera.orbit(vol.bounds, 37, 23, zoom=1.2)
    rgba, _ = render(vol, tf, cam, 20)
    L = box_path_lengths(cam, 20, 20, vol.bounds)
    np.testing.assert_allclose(rgba[..., 3], 1 - 0.6 ** (L / 0.7), atol=1e-9, rtol=0)


# --------------------------------------------------------------------------- linear ramps
RAMP_DIMS = (6, 4, 3)
RAMP_SPACING = (0.5, 1.2, 0.9)


def ramp_volume():
    return grid(lambda x, y, z: x, RAMP_DIMS, RAMP_SPACING)


def x_camera(vol, from_minus):
    b = vol.bounds
    scale = 0.35 * min(b[3] - b[2], b[5] - b[4])  # every pixel centre well inside the y-z face
    return axis_camera(b, (-1, 0, 0) if from_minus else (1, 0, 0), scale, (0, 0, 1))


@pytest.mark.parametrize("from_minus", [True, False])
def test_ramp_constant_opacity_linear_colour_with_kink(from_minus):
    vol = ramp_volume()
    x1 = vol.bounds[1]
    c_pts = [(0.3, 0.1), (1.4, 0.9), (2.0, 0.3)]  # kink at 1.4, constant beyond the ends
    tf = TransferFunction1D([[x, c, 1 - c, 0.5] for x, c in c_pts], [[0, 0.3]], opacity_unit_distance=0.6)
    tau = -math.log(1 - 0.3) / 0.6
    rgba, _ = render(vol, tf, x_camera(vol, from_minus), 6)
    entry, exit_ = (0.0, x1) if from_minus else (x1, 0.0)
    red, alpha = linear_colour_emission(c_pts, tau, entry, exit_)
    green, _ = linear_colour_emission([(x, 1 - c) for x, c in c_pts], tau, entry, exit_)
    np.testing.assert_allclose(rgba[..., 3], alpha, atol=1e-9, rtol=0)
    np.testing.assert_allclose(rgba[..., 0], red, atol=1e-9, rtol=0)
    np.testing.assert_allclose(rgba[..., 1], green, atol=1e-9, rtol=0)
    np.testing.assert_allclose(rgba[..., 2], 0.5 * alpha, atol=1e-9, rtol=0)


def test_ramp_linear_opacity_with_kink():
    vol = ramp_volume()
    a_pts = [(0.0, 0.0), (1.1, 0.9), (1.7, 0.2), (2.5, 0.5)]  # kinks inside the ray
    d = 0.45
    tf = TransferFunction1D([[0, 0.2, 0.7, 1.0]], [list(p) for p in a_pts], opacity_unit_distance=d)
    rgba, _ = render(vol, tf, x_camera(vol, True), 5)
    alpha = 1 - math.exp(-optical_depth_linear_opacity(a_pts, 0.0, vol.bounds[1]) / d)
    np.testing.assert_allclose(rgba[..., 3], alpha, atol=1e-9, rtol=0)
    np.testing.assert_allclose(
        rgba[..., :3], alpha * np.array([0.2, 0.7, 1.0]) * np.ones((5, 5, 1)), atol=1e-9
    )


def test_ramp_opacity_step_is_integrated_exactly():
    """Duplicated control points make a step in opacity: the ray is cut exactly there."""
    vol = ramp_volume()
    tf = TransferFunction1D(
        [[0, 1, 1, 1]], [[0, 0.1], [1.3, 0.1], [1.3, 0.7], [2.5, 0.7]], opacity_unit_distance=1
    )
    rgba, _ = render(vol, tf, x_camera(vol, True), 4)
    od = -math.log(0.9) * 1.3 - math.log(0.3) * (vol.bounds[1] - 1.3)
    np.testing.assert_allclose(rgba[..., 3], 1 - math.exp(-od), atol=1e-9, rtol=0)


def test_empty_and_opaque_limits():
    vol = ramp_volume()
    cam = Camera.orbit(vol.bounds, 25, 15, zoom=0.8)
    empty = TransferFunction1D([[0, 1, 1, 1], [2.5, 1, 0, 0]], [[0, 0.0], [2.5, 0.0]])
    rgba, _ = render(vol, empty, cam, 16)
    assert np.all(rgba == 0)

    # opacity 1 everywhere (clamped to 1 - 1e-6): alpha = 1 - 1e-6^(L/d), colour of the entry
    d = 0.05
    c_pts = [(0.0, 0.2), (2.5, 0.8)]
    tf = TransferFunction1D([[x, c, c, c] for x, c in c_pts], [[0, 1.0]], opacity_unit_distance=d)
    cam = x_camera(vol, True)
    rgba, _ = render(vol, tf, cam, 4)
    L = vol.bounds[1]
    np.testing.assert_allclose(rgba[..., 3], 1 - 1e-6 ** (L / d), atol=1e-9, rtol=0)
    red, _ = linear_colour_emission(c_pts, -math.log(1e-6) / d, 0.0, L)
    np.testing.assert_allclose(rgba[..., 0], red, atol=1e-9, rtol=0)
    np.testing.assert_allclose(rgba[..., 0], 0.2, atol=1e-3)  # the first sample's colour


def test_converged_result_is_independent_of_the_initial_step():
    rng = np.random.default_rng(3)
    vol = UniformVolume(rng.random((7, 6, 8)), spacing=(1.0, 0.8, 1.1))
    tf = TransferFunction1D([[0, 0.9, 0.2, 0.1], [0.5, 0.1, 0.8, 0.3], [1, 0.2, 0.3, 0.9]],
                            [[0.2, 0.0], [0.45, 0.7], [0.5, 0.1], [0.9, 0.5]], opacity_unit_distance=2.0)  # fmt: skip
    cam = Camera.orbit(vol.bounds, 40, 25)
    coarse, _ = render(vol, tf, cam, 20, step=2.0)
    fine, _ = render(vol, tf, cam, 20, step=0.25)
    assert np.abs(coarse - fine).max() < 2e-5
    assert coarse[..., 3].max() > 0.3


# ---------------------------------------------------------------------------- tetrahedra
def linear_field(p):
    return 0.2 + 0.1 * p[..., 0] + 0.15 * p[..., 1] - 0.05 * p[..., 2]


LINEAR_TF = TransferFunction1D(
    [[0, 1, 0, 0], [0.5, 0, 1, 0], [1, 0, 0, 1]], [[0, 0], [0.4, 0.8], [0.6, 0.1], [1, 0.5]]
)


def test_tetrahedra_match_the_uniform_grid_on_a_linear_field():
    dims, spacing = (4, 5, 3), (1.0, 0.7, 1.3)
    uni = grid(lambda x, y, z: linear_field(np.stack([x, y, z], -1)), dims, spacing)
    cam = Camera.orbit(uni.bounds, 30, 20)
    ref, _ = render(uni, LINEAR_TF, cam, 24)
    images = []
    for kind in (6, 5):
        pts, tets = lattice_tets(dims, spacing, kind)
        img, r = render(TetVolume(pts, tets, linear_field(pts)), LINEAR_TF, cam, 24)
        assert r.last_frame.counters["unconverged_rays"] == 0
        assert np.abs(img - ref).max() < 2e-5
        images.append(img)
    assert np.abs(images[0] - images[1]).max() < 2e-5
    assert ref[..., 3].max() > 0.5


@pytest.mark.parametrize("offset", [0.0, 0.5], ids=["through-edges", "in-diagonal-faces"])
def test_rays_along_shared_edges_and_faces(offset):
    """Pixel centres on lattice lines (offset 0: along cube edges shared by up to 6 tets; offset
    0.5: inside the Kuhn diagonal faces x - y = const) give the uniform result, as does a
    slightly shifted camera."""
    dims, spacing = (5, 5, 3), (1.0, 1.0, 0.8)
    pts, tets = lattice_tets(dims, spacing, 6)
    tet = TetVolume(pts, tets, linear_field(pts))
    uni = grid(lambda x, y, z: linear_field(np.stack([x, y, z], -1)), dims, spacing)
    cam = grid_camera(5, 5, 1.0, uni.bounds[5])
    shift = np.array([offset, offset, 0.0])
    cam = Camera(position=np.add(cam.position, shift), focal_point=np.add(cam.focal_point, shift), parallel=True,
                 parallel_scale=cam.parallel_scale, clipping_range=cam.clipping_range)  # fmt: skip
    jiggle = np.array([3e-7, -2e-7, 0.0])
    moved = Camera(position=np.add(cam.position, jiggle), focal_point=np.add(cam.focal_point, jiggle),
                   parallel=True, parallel_scale=cam.parallel_scale, clipping_range=cam.clipping_range)  # fmt: skip
    a, _ = render(tet, LINEAR_TF, cam, 5)
    b, _ = render(tet, LINEAR_TF, moved, 5)
    u, _ = render(uni, LINEAR_TF, cam, 5)
    inner = (slice(1, -1), slice(1, -1))
    assert np.all(np.isfinite(a))
    assert a[inner][..., 3].min() > 0.1
    assert np.abs(a[inner] - u[inner]).max() < 2e-5
    assert np.abs(a[inner] - b[inner]).max() < 2e-5


def test_non_convex_mesh_and_flat_tetrahedra():
    """A cavity in the mesh renders like NaN-transparent cells of the grid; flat cells add nothing."""
    dims, spacing = (5, 4, 4), (0.8, 1.0, 0.9)
    hole = (2, 1, 1)  # the grid point whose eight cells are removed
    cubes = {(hole[0] - a, hole[1] - b, hole[2] - c) for a in (0, 1) for b in (0, 1) for c in (0, 1)}
    pts, tets = lattice_tets(dims, spacing, 5, skip=cubes)
    flat = np.array([[0, 1, dims[0], dims[0] + 1]])  # four points of one face: zero volume
    vol = TetVolume(pts, np.concatenate([tets, flat]), linear_field(pts))
    uni = grid(lambda x, y, z: linear_field(np.stack([x, y, z], -1)), dims, spacing)
    values = uni.values.copy()
    values[hole[2], hole[1], hole[0]] = np.nan
    uni = UniformVolume(values, spacing=spacing)
    cam = Camera.orbit(uni.bounds, 20, 35, zoom=1.4)
    a, r = render(vol, LINEAR_TF, cam, 20)
    u, _ = render(uni, LINEAR_TF, cam, 20)
    assert r.last_frame.counters["flat_or_nonfinite_tets"] == 1
    assert np.abs(a - u).max() < 2e-5


# ------------------------------------------------------------------------- non-finite data
def test_nan_voxels_are_transparent():
    rng = np.random.default_rng(7)
    values = rng.random((6, 7, 8))
    tf = TransferFunction1D.ramp(0.0, 1.0, 0.6, (0.9, 0.5, 0.2))
    cam = Camera.orbit((0, 7, 0, 6, 0, 5), 30, 20)
    half = 4
    nan_half = values.copy()
    nan_half[:, :, half + 1 :] = np.nan
    nan_half[0, 0, half + 2] = np.inf
    full, _ = render(UniformVolume(nan_half), tf, cam, 20)
    alone, _ = render(UniformVolume(np.ascontiguousarray(values[:, :, : half + 1])), tf, cam, 20)
    assert np.all(np.isfinite(full))
    assert np.abs(full - alone).max() < 1e-7
    assert alone[..., 3].max() > 0.3

    speckled = values.copy()
    speckled[2, 3, 4] = np.nan
    speckled[4, 1, 1] = -np.inf
    for mode in BlendMode:
        img, _ = render(UniformVolume(speckled), tf, cam, 16, blend_mode=mode)
        assert np.all(np.isfinite(img)) and img[..., 3].max() > 0


def test_nan_point_values_drop_their_tetrahedra():
    dims, spacing = (4, 4, 3), (1.0, 1.0, 1.0)
    pts, tets = lattice_tets(dims, spacing, 6)
    values = linear_field(pts)
    values[5] = np.nan
    img, r = render(TetVolume(pts, tets, values), LINEAR_TF, Camera.orbit((0, 3, 0, 3, 0, 2), 30, 20), 16)
    assert np.all(np.isfinite(img)) and img[..., 3].max() > 0.1
    assert r.last_frame.counters["flat_or_nonfinite_tets"] == np.count_nonzero((tets == 5).any(axis=1))


# ---------------------------------------------------------------------------- blend modes
@pytest.mark.parametrize("mode", [BlendMode.MAXIMUM, BlendMode.MINIMUM, BlendMode.AVERAGE])
def test_projection_modes_along_grid_lines(mode):
    rng = np.random.default_rng(11)
    nx, ny, nz, s = 7, 6, 5, 0.5
    values = rng.random((nz, ny, nx))
    vol = UniformVolume(values, spacing=(s, s, 1.3))
    tf = TransferFunction1D([[0, 0.1, 0.9, 0.3], [1, 0.8, 0.2, 0.6]], [[0.1, 0.0], [0.9, 1.0]])
    cam = grid_camera(nx, ny, s, vol.bounds[5])
    rgba, _ = render(vol, tf, cam, nx, ny, blend_mode=mode)
    if mode is BlendMode.MAXIMUM:
        v = values.max(axis=0)
    elif mode is BlendMode.MINIMUM:
        v = values.min(axis=0)
    else:  # along a grid line the trilinear interpolant is piecewise linear in z
        v = (values.sum(axis=0) - 0.5 * (values[0] + values[-1])) / (nz - 1)
    rgb, alpha = tf.sample(v[::-1])  # row 0 is the top (largest y)
    expect = np.concatenate([rgb * alpha[..., None], alpha[..., None]], axis=-1)
    np.testing.assert_allclose(rgba[1:-1, 1:-1], expect[1:-1, 1:-1], atol=1e-12, rtol=0)


def test_projection_modes_on_tetrahedra_match_the_grid():
    dims, spacing = (4, 5, 3), (1.0, 0.7, 1.3)
    pts, tets = lattice_tets(dims, spacing, 5)
    tet = TetVolume(pts, tets, linear_field(pts))
    uni = grid(lambda x, y, z: linear_field(np.stack([x, y, z], -1)), dims, spacing)
    cam = Camera.orbit(uni.bounds, 30, 20)
    for mode in (BlendMode.MAXIMUM, BlendMode.MINIMUM, BlendMode.AVERAGE):
        a, _ = render(tet, LINEAR_TF, cam, 16, blend_mode=mode)
        u, _ = render(uni, LINEAR_TF, cam, 16, blend_mode=mode)
        assert np.abs(a - u).max() < 1e-9
        assert a[..., 3].max() > 0.1


# --------------------------------------------------------------------------------- shading
SHADE = dict(shade=True, ambient=0.3, diffuse=0.9, specular=0.4, specular_power=7.0)


def expected_shading(cam, width, c, normal):
    """Closed form of the shaded colour per pixel for a constant normal (before flipping)."""
    _, d = cam.pixel_rays(width, width)
    light = -np.asarray(cam.direction)
    half = light - d
    half /= np.linalg.norm(half, axis=-1, keepdims=True)
    n = np.asarray(normal, float)
    if n @ light < 0:
        n = -n
    ndl = n @ light
    spec = SHADE["specular"] * np.maximum(half @ n, 0.0) ** SHADE["specular_power"]
    return np.clip(np.asarray(c) * (SHADE["ambient"] + SHADE["diffuse"] * ndl) + spec[..., None], 0, 1)


@pytest.mark.parametrize("kind", ["uniform", "tet"])
def test_shading_of_a_constant_gradient_field(kind):
    dims, spacing = (5, 4, 3), (0.8, 1.1, 0.9)
    if kind == "uniform":
        vol = grid(lambda x, y, z: x, dims, spacing)
    else:
        pts, tets = lattice_tets(dims, spacing, 6)
        vol = TetVolume(pts, tets, pts[:, 0].copy())
    c = (1.0, 0.6, 0.3)
    tf = TransferFunction1D.constant(0.3, c, opacity_unit_distance=1.2)
    cam = Camera.orbit(vol.bounds, 70, -25, zoom=1.2)
    rgba, _ = render(vol, tf, cam, 16, **SHADE)
    L = box_path_lengths(cam, 16, 16, vol.bounds)
    alpha = 1 - 0.7 ** (L / 1.2)
    shaded = expected_shading(cam, 16, c, (-1.0, 0.0, 0.0))  # N = -grad s / |grad s|
    np.testing.assert_allclose(rgba[..., 3], alpha, atol=1e-9, rtol=0)
    np.testing.assert_allclose(rgba[..., :3], shaded * alpha[..., None], atol=1e-9, rtol=0)
    assert (shaded[..., 0] == 1.0).any()  # the clamp was exercised


def test_zero_gradient_is_not_shaded():
    vol = UniformVolume(np.full((3, 4, 5), 2.0))
    tf = TransferFunction1D.constant(0.5, (0.4, 0.5, 0.6))
    cam = Camera.orbit(vol.bounds, 30, 20)
    lit, _ = render(vol, tf, cam, 12, **SHADE)
    plain, _ = render(vol, tf, cam, 12)
    np.testing.assert_array_equal(lit, plain)


# ------------------------------------------------------------------------------- invariants
@pytest.mark.parametrize("seed", range(4))
def test_invariants_on_random_volumes(seed):
    rng = np.random.default_rng(seed)
    dims = tuple(int(n) for n in rng.integers(2, 7, 3))
    vol = UniformVolume(rng.random(dims[::-1]) * 10 - 3, spacing=tuple(rng.uniform(0.3, 2.0, 3)))
    xs = np.sort(rng.uniform(-4, 8, 5))
    tf = TransferFunction1D(np.column_stack([xs, rng.random((5, 3))]), np.column_stack([xs, rng.random(5)]),
                            opacity_unit_distance=float(rng.uniform(0.1, 3)))  # fmt: skip
    cam = Camera.orbit(
        vol.bounds, *rng.uniform(-180, 180, 2), zoom=float(rng.uniform(0.7, 2)), parallel=seed % 2 == 1
    )
    for mode in BlendMode:
        for shade in (False, True):
            img, r = render(vol, tf, cam, 12, 10, blend_mode=mode, shade=shade)
            assert np.all(np.isfinite(img))
            assert img.min() >= 0 and img.max() <= 1
            assert np.all(img[..., :3] <= img[..., 3:4])
            assert r.last_frame.counters["unconverged_rays"] == 0


# ------------------------------------------------------------------------ renderer contract
def test_counters_progress_and_options():
    vol = ramp_volume()
    r = ReferenceRenderer()
    r.set_volume(vol)
    r.set_transfer_function(LINEAR_TF)
    seen = []
    r.render(Camera.orbit(vol.bounds, 10, 10), 8, 40, progress=seen.append)
    assert seen == sorted(seen) and seen[-1] == 1.0 and len(seen) > 1
    counters = r.last_frame.counters
    for key in ("samples", "unconverged_rays", "max_level", "mean_level", "subdivision_cap_hits"):
        assert key in counters
    assert counters["samples"] > 0
    assert r.capabilities.volume_kinds == {"uniform", "tet"}
    assert set(r.capabilities.kinds["tet"].blend_modes) == set(BlendMode)

    with pytest.raises(VolrenError, match="no option"):
        r.set_settings(RenderSettings(options={"tolerence": 1e-4}))
    with pytest.raises(VolrenError, match="tolerance"):
        r.set_settings(RenderSettings(options={"tolerance": -1.0}))
    with pytest.raises(VolrenError, match="max_levels"):
        r.set_settings(RenderSettings(options={"max_levels": 1}))

    r.set_settings(RenderSettings(options={"tolerance": 1e-14, "max_levels": 2}))
    with pytest.warns(VolrenWarning, match="did not converge"):
        r.render(Camera.orbit(vol.bounds, 10, 10), 8, 8)
    assert r.last_frame.counters["unconverged_rays"] > 0


def test_iron_protein_scene():
    path = SHARED / "data" / "uniform" / "ironProt.vtk"
    if not path.exists():
        pytest.skip(f"{SHARED_MISSING}: {path} not found")
    import pyvista as pv

    grid_ = pv.read(path)
    grid_.set_active_scalars("scalars")
    vol = UniformVolume(np.asarray(grid_.active_scalars).reshape(tuple(grid_.dimensions)[::-1]),
                        spacing=grid_.spacing, origin=grid_.origin)  # fmt: skip
    tf = TransferFunction1D.from_dict(json.loads((SHARED / "scenes" / "ironProt-spiky.json").read_text()))
    img, r = render(vol, tf, Camera.orbit(vol.bounds, 30, 20), 24)
    assert r.last_frame.counters["unconverged_rays"] == 0
    assert img[..., 3].max() > 0.5 and np.all(img[..., :3] <= img[..., 3:4])
