"""The shear-warp plugin: the conformance kit, the factorization's exactness, pre-integration
against post-classification, the skipping techniques changing nothing they should not, and bad
input (thin, constant, NaN, anisotropic volumes, axis-aligned and diagonal views, an eye inside)."""

from __future__ import annotations

import inspect
import math
from dataclasses import replace
from functools import partial

import numpy as np
import pytest
from volren_shearwarp import ShearWarpRenderer
from volren_shearwarp.classified import RANGE_BINS, OpacitySupport, block_ranges, slab_pairs
from volren_shearwarp.composite import interior_pixels
from volren_shearwarp.factorization import factorize
from volren_shearwarp.renderer import (
    auto_oversampling,
    auto_table_size,
    slice_stride,
    strided_order,
    voxel_optical_depth,
)

from volren.errors import VolrenError
from volren.kernels.shading import gradient_threshold
from volren.model import BlendMode, Camera, RenderSettings, TransferFunction1D, UniformVolume
from volren.model.downsample import downsample
from volren.testing import conformance_test, image_error, oracles
from volren.testing.reference_images import reference_image
from volren.testing.render_helpers import SMOOTH_TF, clipped_constant_box, field, render_checked
from volren.testing.scenes import distant_camera_cut_by_far_plane

# one pytest test per check of the kit
test_conformance = conformance_test(ShearWarpRenderer, quick=True)

draw = partial(render_checked, ShearWarpRenderer)


# ---------------------------------------------------------------------------------- geometry
@pytest.mark.parametrize("parallel", [False, True])
@pytest.mark.parametrize(
    "azimuth, elevation", [(0, 0), (90, 0), (0, 90), (45, 0), (45, 35.26), (30, 20), (-120, -50)]
)
def test_a_bright_voxel_lands_where_the_camera_projects_it(parallel, azimuth, elevation):
    """The factorization and the warp are exact: one bright lattice point's blob is centred on the
    camera's projection of it (axis-aligned, 45 degree and body-diagonal views, both projections)."""
    dims, spacing, origin = (13, 11, 9), (1.0, 1.3, 0.8), (-2.0, 1.0, 0.5)
    bright = (8, 3, 5)
    values = np.zeros(dims[::-1], np.float32)
    values[bright[2], bright[1], bright[0]] = 1.0
    volume = UniformVolume(values, spacing=spacing, origin=origin)
    point = [o + s * i for o, s, i in zip(origin, spacing, bright, strict=True)]
    tf = TransferFunction1D([[0, 1, 1, 1]], [[0, 0.0], [1, 0.9]], opacity_unit_distance=0.5)
    w, h = 70, 50
    camera = Camera.orbit(volume.bounds, azimuth, elevation, zoom=1.5, parallel=parallel, aspect=w / h)
    image, _ = draw(volume, tf, camera, (w, h))
    cx, cy = oracles.weighted_centroid(image[..., 3])
    px, py = oracles.pixel_of(camera, w, h, point)
    assert math.hypot(cx - px, cy - py) < 0.35


def test_the_principal_axis_is_the_steepest_and_the_shear_at_most_one():
    volume = field()
    for az, el in [(0, 0), (40, 10), (80, 0), (10, 80), (45, 35.26)]:
        fac = factorize(Camera.orbit(volume.bounds, az, el, parallel=True), volume, 64, 64, 1.0)
        assert fac.max_shear <= 1.0 + 1e-9
        assert fac.slab_length > 0


@pytest.mark.parametrize("slices, stride", [(16, 1), (16, 2), (16, 3), (16, 5), (13, 4), (9, 8)])
@pytest.mark.parametrize("forward", [True, False])
def test_strided_slabs_cover_the_slices_once_and_match_their_runs(slices, stride, forward):
    """The compositing order's slabs (every stride-th slice from the front, the last slice kept) are
    the runs' slab pairs, in the renderer's numbering (`run_slab`: by lower slice), and cover
    every slice interval once; only the back slab may be short."""
    order = np.arange(slices) if forward else np.arange(slices - 1, -1, -1)
    picked, frac = strided_order(order, stride)
    pairs, run_slab = slab_pairs(picked)
    assert picked[0] == order[0] and picked[-1] == order[-1]
    for m in range(1, len(picked)):
        lower, upper = sorted((picked[m - 1], picked[m]))
        assert tuple(pairs[run_slab[m]]) == (lower, upper)
        assert frac[m] == pytest.approx((upper - lower) / stride)
    assert np.all(frac[1:-1] == 1.0) and 0 < frac[-1] <= 1.0
    assert pairs[0, 0] == 0 and pairs[-1, 1] == slices - 1 and np.all(pairs[1:, 0] == pairs[:-1, 1])
    assert slice_stride(0.5, 1.0, 1.0, slices) == 1 and slice_stride(1.0, 1.0, 1.0, slices) == 2
    assert slice_stride(100.0, 1.0, 1.0, 3) == 2  # never past the volume


# ------------------------------------------------------------------------------ accuracy
def test_preintegration_beats_post_classification_on_a_spiky_tf():
    """Same slices, same camera, default oversampling: against the reference the pre-integrated error
    is at least 3x lower (at oversampling 1 the warp's blur of the thin shells dominates both)."""
    volume = field((12, 12, 12))
    spiky = TransferFunction1D([[-2, 0.9, 0.9, 0.2], [4, 0.2, 0.6, 1.0]],
                               [[0.9, 0.0], [1.0, 0.9], [1.1, 0.0]], opacity_unit_distance=1.0)  # fmt: skip
    camera = Camera.orbit(volume.bounds, 30, 20, zoom=1.2)
    size = (48, 48)
    truth = reference_image(volume, spiky, camera, *size)
    pre, _ = draw(volume, spiky, camera, size, preintegration=True)
    post, _ = draw(volume, spiky, camera, size, preintegration=False)
    e_pre, e_post = image_error(pre, truth).rmse, image_error(post, truth).rmse
    assert e_pre * 3 <= e_post, (e_pre, e_post)


def test_a_smooth_tf_matches_the_reference():
    volume = field()
    camera = Camera.orbit(volume.bounds, 30, 20)
    truth = reference_image(volume, SMOOTH_TF, camera, 40, 32)
    for pre in (False, True):
        image, _ = draw(volume, SMOOTH_TF, camera, preintegration=pre)
        assert image_error(image, truth).rmse < 0.01


@pytest.mark.parametrize("pre", [False, True])
def test_downsample_draws_the_coarse_volume_and_keeps_the_full_one(pre):
    """The option renders `volren.model.downsample`'s copy exactly as if that copy were the volume,
    the tables still span the full data's value range, and the full level is untouched."""
    volume = field((33, 29, 35))
    coarse = downsample(volume, 2)
    camera = Camera.orbit(volume.bounds, 30, 20)
    direct, direct_renderer = draw(coarse, SMOOTH_TF, camera, preintegration=pre)
    image, renderer = draw(volume, SMOOTH_TF, camera, preintegration=pre, options={"downsample": 2})
    # equal up to the table range (the coarse copy's value range is a little narrower than the full one)
    assert image_error(image, direct).rmse < 2e-3
    counters, coarse_counters = renderer.last_frame.counters, direct_renderer.last_frame.counters
    assert counters["slices"] == coarse_counters["slices"]
    assert abs(counters["samples"] - coarse_counters["samples"]) <= 1e-3 * coarse_counters["samples"]
    full, _ = draw(volume, SMOOTH_TF, camera, preintegration=pre)
    renderer.set_settings(RenderSettings(preintegration=pre))
    assert np.array_equal(renderer.render(camera, 40, 32), full)
    truth = reference_image(volume, SMOOTH_TF, camera, 40, 32)
    assert image_error(image, truth).rmse < 0.03  # a draft, coarser than the default's 0.01


@pytest.mark.parametrize("pre", [False, True])
def test_fewer_pixels_per_voxel_draw_a_coarser_draft_of_the_same_image(pre):
    """`pixels_per_voxel` below 1 narrows the intermediate image by that factor along each axis (about
    its square of the segments), a smooth field stays near the reference as a draft, and 1 is the
    default to the bit (skipping stays exact: the skipping tests run at 0.6 and 0.5 too)."""
    volume = field((24, 26, 28))
    camera = Camera.orbit(volume.bounds, 30, 20)
    size = (64, 64)
    coarse = {"oversampling": 0.25, "pixels_per_voxel": 0.7}
    full, r_full = draw(volume, SMOOTH_TF, camera, size, preintegration=pre, options={"oversampling": 0.25})
    draft, r_draft = draw(volume, SMOOTH_TF, camera, size, preintegration=pre, options=coarse)
    default, _ = draw(volume, SMOOTH_TF, camera, size, preintegration=pre,
                      options={"oversampling": 0.25, "pixels_per_voxel": 1.0})  # fmt: skip
    assert np.array_equal(default, full)
    c_full, c_draft = r_full.last_frame.counters, r_draft.last_frame.counters
    for side in ("intermediate_width", "intermediate_height"):
        assert 0.6 < c_draft[side] / c_full[side] < 0.8, (side, c_draft[side], c_full[side])
    assert 0.35 < c_draft["samples"] / c_full["samples"] < 0.65
    truth = reference_image(volume, SMOOTH_TF, camera, *size)
    e_full, e_draft = image_error(full, truth).rmse, image_error(draft, truth).rmse
    assert e_full < e_draft < min(2 * e_full, 0.03), (e_full, e_draft)  # measured: 0.0175 and 0.0275


@pytest.mark.parametrize(
    "dtype, kept",
    [
        pytest.param(np.uint8, np.uint8, marks=pytest.mark.slow),  # about 6 s: compiles the uint8 kernels
        (np.uint16, np.float32),
        (np.int16, np.float32),
    ],
)
def test_8_bit_volumes_keep_their_type_in_the_axis_copies_and_draw_as_float32_ones(dtype, kept, monkeypatch):
    """uint8 data stays uint8 in the three copies (a quarter of float32's memory), and every path
    that reads them (fast spans, the general way, gradients for shading, the projections, jitter)
    draws exactly what float32 copies draw: differences of unsigned values must not wrap around, so
    the kernels convert each value to float32 first. 16-bit data gets float32 copies (`copy_dtype`)."""
    import volren_shearwarp.classified as classified

    values = field((14, 16, 18)).values
    low = 0 if np.dtype(dtype).kind == "u" else -300
    scaled = np.round(low + (values - values.min()) / np.ptp(values) * (250 - low)).astype(dtype)
    volume = UniformVolume(scaled)
    tf = TransferFunction1D([[low, 0.2, 0.3, 1.0], [250, 1.0, 0.8, 0.1]], [[low + 20, 0.0], [250, 0.6]], 20.0)
    camera = Camera.orbit(volume.bounds, 30, 20)
    variants = [{"preintegration": True}, {"preintegration": False, "step": 1.0},
                {"preintegration": True, "shade": True}, {"blend_mode": "maximum"}, {"jitter": True}]  # fmt: skip
    for settings in variants:
        image, renderer = draw(volume, tf, camera, **settings)
        assert renderer.classified.copy(0).values.dtype == np.dtype(kept)
        assert renderer.classified.copy(0).values.nbytes == scaled.size * np.dtype(kept).itemsize
        monkeypatch.setattr(classified, "copy_dtype", lambda _: np.dtype(np.float32))
        as_float, _ = draw(volume, tf, camera, **settings)
        monkeypatch.undo()
        assert image[..., 3].max() > 0.1
        np.testing.assert_array_equal(image, as_float, err_msg=str(settings))


# ----------------------------------------------------------------------------- skipping
@pytest.mark.parametrize("parallel", [False, True])
@pytest.mark.parametrize("step, azimuth", [(0.5, 35), (1.0, 35), (1.0, 215), (2.0, 215)])
@pytest.mark.parametrize("pixels_per_voxel", [1.0, 0.6])
def test_empty_space_skipping_changes_no_pixel(parallel, step, azimuth, pixels_per_voxel):
    """Also with slices skipped (step 1 and 2: slabs of 2 and 4 slices, a short one at the back, the
    order running both ways), and with intermediate pixels wider than voxels. At step 2 the runs'
    blocks span 4 cells per unit of shear, which on 16 cells leaves little to skip: 31 there."""
    volume = field((16, 16, 16) if step < 2 else (31, 31, 31))
    tf = TransferFunction1D(
        [[-2, 1, 0.5, 0.2], [4, 0.3, 0.6, 1.0]], [[1.4, 0.0], [1.6, 0.7], [2.0, 0.0]], 1.0
    )
    camera = Camera.orbit(volume.bounds, azimuth, 25, parallel=parallel)
    options = {"oversampling": 0.25, "pixels_per_voxel": pixels_per_voxel}
    on, r_on = draw(
        volume, tf, camera, preintegration=True, step=step, options=options | {"empty_space_skipping": True}
    )
    off, r_off = draw(volume, tf, camera, preintegration=True, step=step,
                      options=options | {"empty_space_skipping": False})  # fmt: skip
    assert factorize(camera, volume, 40, 32, 0.25, min_scale=pixels_per_voxel).scale == pixels_per_voxel
    assert r_on.last_frame.counters["slice_stride"] == 2 * step
    assert r_on.last_frame.counters["empty_pixels_skipped"] > 0
    assert r_on.last_frame.counters["samples"] < r_off.last_frame.counters["samples"]
    np.testing.assert_array_equal(on, off)


@pytest.mark.parametrize("pre", [False, True])
@pytest.mark.parametrize("step, pixels_per_voxel", [(0.5, 1.0), (1.0, 1.0), (0.5, 0.5)])
def test_empty_space_skipping_changes_no_pixel_where_rays_fan_out_both_ways(pre, step, pixels_per_voxel):
    """A wide perspective view whose eye faces the middle of the volume: rays move towards larger
    and smaller a and b across the slabs, so every row picks the runs' blocks on both sides of its
    split and rows pick both row blocks (`classified`'s anchored blocks); a narrow TF peak over
    sparse blobs, so a block on the wrong side would drop a visible segment."""
    rng = np.random.default_rng(7)
    values = np.zeros((24, 26, 28), np.float32)
    for _ in range(40):
        k, j, i = rng.integers(1, 23), rng.integers(1, 25), rng.integers(1, 27)
        values[k - 1 : k + 2, j - 1 : j + 2, i - 1 : i + 2] += rng.uniform(0.5, 2.0)
    volume = UniformVolume(values)
    tf = TransferFunction1D([[0, 1, 0.6, 0.2], [3, 0.2, 0.5, 1.0]], [[0.9, 0.0], [1.0, 0.8], [1.1, 0.0]], 1.0)
    centre = np.array([13.5, 12.5, 11.5])
    camera = Camera(position=tuple(centre + [3.0, 2.0, -24.0]), focal_point=tuple(centre), view_angle=70.0,
                    clipping_range=(1.0, 80.0))  # fmt: skip
    fac = factorize(camera, volume, 60, 50, 1.0)
    assert 1.0 < fac.max_shear <= 3.0
    assert 0 < fac.eye[0] < 27 and 0 < fac.eye[1] < 25  # the eye faces the slices: shifts of both signs
    options = {"pixels_per_voxel": pixels_per_voxel, "oversampling": 0.25}
    on, r_on = draw(volume, tf, camera, (60, 50), preintegration=pre, step=step,
                    options=options | {"empty_space_skipping": True})  # fmt: skip
    off, _ = draw(volume, tf, camera, (60, 50), preintegration=pre, step=step,
                  options=options | {"empty_space_skipping": False})  # fmt: skip
    assert r_on.last_frame.counters["empty_pixels_skipped"] > 0 and on[..., 3].max() > 0.1
    np.testing.assert_array_equal(on, off)


@pytest.mark.parametrize("settings", [
    {"preintegration": True}, {"preintegration": False, "step": 1.0}, {"preintegration": True, "shade": True},
    {"preintegration": True, "step": 0.25, "jitter": True}, {"blend_mode": BlendMode.MAXIMUM},
    {"blend_mode": BlendMode.AVERAGE},
])  # fmt: skip
def test_blocks_of_rows_draw_every_row_as_one_row_at_a_time_does(monkeypatch, settings):
    """The kernels composite `ROW_BLOCK` intermediate rows together, slab by slab; each pixel's
    arithmetic is the same whatever the block, so the image and the counters must not change to the
    bit: blocks of 1 row (row after row), 3 (a short last block: the intermediate image here is 29
    rows high, not a multiple of 3), 8 (the default) and 64 (one block larger than the image).
    Opaque blobs make rows terminate early at different slabs; a perspective view under a far plane
    that cuts the volume takes the clipped path too."""
    rng = np.random.default_rng(11)
    values = rng.uniform(0.0, 0.4, (20, 22, 24)).astype(np.float32)
    values[5:9, 6:12, 4:14] += 2.0
    volume = UniformVolume(values)
    tf = TransferFunction1D(
        [[0, 1, 0.6, 0.2], [2.4, 0.2, 0.5, 1.0]], [[0.1, 0.0], [0.4, 0.3], [2.0, 1.0]], 1.0
    )
    camera = Camera.orbit(volume.bounds, 30, 20)
    behind_the_centre = float(np.linalg.norm(np.subtract(camera.position, camera.focal_point))) + 2.0
    camera = replace(camera, clipping_range=(1.0, behind_the_centre))
    drawn = {}
    for rows in (1, 3, 8, 64):
        monkeypatch.setattr("volren_shearwarp.renderer.ROW_BLOCK", rows)
        image, renderer = draw(volume, tf, camera, (48, 40), options={"oversampling": 0.75}, **settings)
        drawn[rows] = image, dict(renderer.last_frame.counters)
    image, counters = drawn[1]
    assert counters["intermediate_height"] % 3 != 0 and counters["intermediate_height"] < 64
    assert image[..., 3].max() > 0.25  # something is drawn (the average of the blobs' opacity is about 0.3)
    if "blend_mode" not in settings:
        assert counters["clipped"] == 1.0 and counters["pixels_terminated"] > 0
    for rows in (3, 8, 64):
        np.testing.assert_array_equal(drawn[rows][0], image)
        assert drawn[rows][1] == counters


def test_interior_pixels_keep_both_ends_strictly_inside_the_row():
    """The fast path reads columns floor(a) and floor(a) + 1 unclamped, so the pixels it takes have
    both segment ends in [0, top): also where a sample lands exactly on the last column (one
    intermediate pixel per voxel, integer shifts), where it once read one past the row
    (found with NUMBA_BOUNDSCHECK=1, skipping off, the CT sample)."""
    rng = np.random.default_rng(3)
    top, width = 20.0, 64
    cases = [(0.0, 1.0, 0.0, 1.0), (-3.0, 1.0, -2.0, 1.0), (0.5, 0.5, 0.25, 0.5), (-7.0, 1.0, -5.0, 1.0)]
    cases += [tuple(rng.uniform([-10, 0.3, -10, 0.3], [5, 2.0, 5, 2.0])) for _ in range(300)]
    for af0, afs, ab0, abs_ in cases:
        lo, hi = interior_pixels(af0, afs, ab0, abs_, top, 0, width)
        inside = [p for p in range(width) if 0 <= af0 + afs * p < top and 0 <= ab0 + abs_ * p < top]
        assert list(range(lo, hi)) == inside, (af0, afs, ab0, abs_)
    # the exact case: pixel 20 samples column 20 == top exactly and must go the general way
    assert interior_pixels(0.0, 1.0, 0.0, 1.0, top, 0, width) == (0, 20)


@pytest.mark.parametrize("extent", [1, 2, 3])
def test_block_ranges_are_the_anchored_blocks_vertex_ranges(extent):
    """`_block_ranges` against a brute-force oracle: block (j, i) of a slab is cells j - extent .. j by
    i - extent .. i, clipped to the slice, its range over their vertices in both slices, NaN left out."""
    rng = np.random.default_rng(extent)
    values = rng.uniform(-1.0, 3.0, (5, 7, 9)).astype(np.float32)
    values[2, 3, 4] = np.nan
    values[1, :2, :2] = np.nan  # a slab's corner block with no finite vertex
    support = OpacitySupport.of(SMOOTH_TF, -1.0, 3.0)
    pairs = slab_pairs(np.arange(5))[0]
    bmin, bmax = block_ranges(values, support, extent, pairs)
    bins = support.counts.shape[0] - 1
    shift = int(math.log2(bins // RANGE_BINS))
    nc, nb, na = values.shape
    assert bmin.shape == (4, nb - 1 + extent, na - 1 + extent)
    for k, (k0, k1) in enumerate(pairs):
        for j in range(nb - 1 + extent):
            for i in range(na - 1 + extent):
                block = values[
                    [k0, k1],
                    max(j - extent, 0) : min(j + 1, nb - 1) + 1,
                    max(i - extent, 0) : min(i + 1, na - 1) + 1,
                ]
                finite = block[np.isfinite(block)]
                if finite.size == 0:
                    assert (bmin[k, j, i], bmax[k, j, i]) == (RANGE_BINS - 1, 0)
                    continue
                to_bin = [min(max(int((np.float32(v) + 1.0) * (bins / 4.0)), 0), bins - 1) >> shift
                          for v in (finite.min(), finite.max())]  # fmt: skip
                assert (bmin[k, j, i], bmax[k, j, i]) == tuple(to_bin), (k, j, i)


@pytest.mark.parametrize("pre", [False, True])
def test_empty_space_skipping_is_exact_on_a_ct_sample(pre):
    """The bundled CT phantom with its narrow TF peak: before the runs were built separably, skipping
    changed 449 of its 64x64 pixels by up to 0.09 post-classified (`volren bench skip` found it)."""
    from volren.io import load_transfer_function, load_volume
    from volren.samples import sample_paths

    volume_path, tf_path = sample_paths("phantom_ct")[:2]
    volume, tf = load_volume(volume_path), load_transfer_function(tf_path)
    camera = Camera.orbit(volume.bounds, 30, 20)
    on, r_on = draw(volume, tf, camera, (64, 64), preintegration=pre, options={"empty_space_skipping": True})
    off, _ = draw(volume, tf, camera, (64, 64), preintegration=pre, options={"empty_space_skipping": False})
    assert r_on.last_frame.counters["empty_pixels_skipped"] > 0
    np.testing.assert_array_equal(on, off)


def test_early_termination_stops_opaque_pixels_and_changes_little():
    volume = field()
    opaque = TransferFunction1D([[-2, 1, 1, 1]], [[-2, 0.0], [0.0, 1.0]], 1.0)
    camera = Camera.orbit(volume.bounds, 30, 20)
    on, r_on = draw(volume, opaque, camera, options={"early_termination": True, "termination_alpha": 0.99})
    off, r_off = draw(volume, opaque, camera, options={"early_termination": False})
    assert r_on.last_frame.counters["pixels_terminated"] > 0
    assert r_on.last_frame.counters["samples"] < r_off.last_frame.counters["samples"]
    assert np.abs(on - off).max() <= 0.011


def test_a_colour_edit_reuses_the_runs_and_an_opacity_edit_rebuilds_them():
    volume = field()
    tf = SMOOTH_TF.copy()
    camera = Camera.orbit(volume.bounds, 30, 20, parallel=True)
    renderer = ShearWarpRenderer()
    renderer.set_volume(volume)
    renderer.set_transfer_function(tf)
    renderer.render(camera, 24, 24)
    copy = renderer.classified.copies[next(iter(renderer.classified.copies))]
    runs = dict(copy.runs)
    tf.set_color_points([[-2, 0.0, 1.0, 0.0], [4, 1.0, 0.0, 1.0]])
    renderer.render(camera, 24, 24)
    assert all(copy.runs[r] is runs[r] for r in runs)  # same objects: nothing rebuilt
    tf.set_opacity_points([[-1, 0.0], [4, 0.3]])  # other values, same support
    renderer.render(camera, 24, 24)
    assert all(copy.runs[r] is runs[r] for r in runs)
    tf.set_opacity_points([[2.5, 0.0], [4, 0.6]])  # the support shrinks
    renderer.render(camera, 24, 24)
    assert any(copy.runs[r] is not runs[r] for r in runs)


@pytest.mark.parametrize("pre", [False, True])
@pytest.mark.parametrize("parallel", [True, False])
def test_opacity_correction_off_draws_each_slab_as_one_unit_distance(pre, parallel):
    """The NC variant of Schulze et al.'s Table 1: every slab gets the TF's opacity as it is, whatever its length (here
    spacing 0.5 against d_u 1: 31 slabs of half a unit). On, the closed form 1 - (1 - a)^(L / d_u)."""
    a = 0.05
    volume = UniformVolume(np.full((32, 32, 32), 2.0, np.float32), spacing=(0.5, 0.5, 0.5))
    tf = TransferFunction1D([[0, 1, 1, 1], [4, 1, 1, 1]], [[0, a], [4, a]])
    c = 7.75
    camera = Camera(position=(c, c, 40.0), focal_point=(c, c, c), parallel=parallel, parallel_scale=12.0,
                    view_angle=40.0, clipping_range=(1.0, 100.0))  # fmt: skip
    on, _ = draw(volume, tf, camera, (16, 16), preintegration=pre)
    off, _ = draw(volume, tf, camera, (16, 16), preintegration=pre, options={"opacity_correction": False})
    assert on[8, 8, 3] == pytest.approx(1 - (1 - a) ** (31 * 0.5), abs=2e-3)
    if parallel:  # every ray crosses 31 slabs
        assert off[8, 8, 3] == pytest.approx(1 - (1 - a) ** 31, abs=2e-3)
    else:  # central rays cross the same 31 slabs, longer ones off the axis: one opacity without correction
        centre_on, centre_off = on[5:11, 5:11, 3], off[5:11, 5:11, 3]
        assert np.ptp(centre_off) < 1e-4 < 1e-3 < np.ptp(centre_on)
        assert centre_off.mean() == pytest.approx(1 - (1 - a) ** 31, abs=2e-3)


# ----------------------------------------------------------------------------- bad input
def test_a_grid_one_sample_thick_is_refused_by_the_model_and_two_samples_render():
    with pytest.raises(VolrenError):
        UniformVolume(np.zeros((1, 5, 5), np.float32))
    for shape in [(2, 9, 9), (9, 2, 9), (9, 9, 2)]:
        volume = UniformVolume(np.random.default_rng(1).random(shape).astype(np.float32))
        for parallel in (False, True):
            for pre in (False, True):
                image, _ = draw(volume, SMOOTH_TF, Camera.orbit(volume.bounds, 30, 20, parallel=parallel),
                                preintegration=pre)  # fmt: skip
                assert image[..., 3].max() > 0


def test_a_constant_volume_draws_the_closed_form():
    volume = UniformVolume(np.full((6, 7, 8), 1.0, np.float32), spacing=(0.9, 1.1, 1.0))
    tf = TransferFunction1D.constant(0.3, (0.4, 0.7, 0.2), opacity_unit_distance=0.8)
    for parallel in (False, True):
        camera = Camera.orbit(volume.bounds, 25, 15, zoom=1.3, parallel=parallel)
        image, _ = draw(volume, tf, camera, (40, 40), preintegration=True)
        expected = oracles.homogeneous_image(oracles.box_path_lengths(camera, 40, 40, volume.bounds),
                                             (0.4, 0.7, 0.2), 0.3, 0.8)  # fmt: skip
        assert image_error(image, expected).rmse < 0.03


@pytest.mark.parametrize("pre", [False, True])
@pytest.mark.parametrize("step", [1.0, 1.5, 2.0])
def test_skipped_slices_keep_the_closed_form_of_a_constant_volume(pre, step):
    """Every stride-th slice (2, 3, 4 of 6 slices here): each segment spans stride slices and takes the
    table for that length, and the short last slab (the stride divides no slice count here) is
    corrected to its length, so a constant volume draws what every slice draws, both projections."""
    volume = UniformVolume(np.full((6, 7, 8), 1.0, np.float32), spacing=(1.0, 1.1, 1.0))
    tf = TransferFunction1D.constant(0.3, (0.4, 0.7, 0.2), opacity_unit_distance=0.8)
    for parallel in (False, True):
        camera = Camera.orbit(volume.bounds, 25, 15, zoom=1.3, parallel=parallel)
        fac = factorize(camera, volume, 40, 40, 1.0)
        stride = slice_stride(step, fac.spacing[2], volume.characteristic_length, len(fac.order))
        assert stride >= 2 and (len(fac.order) - 1) % stride != 0
        # under perspective each pixel's segment length snaps to a grid (`length_ratio`, 1.02 by default:
        # opacity off by up to 1 % of its optical depth, the two images 0.004 apart here; 20x finer, 0.0002)
        fine = {"length_ratio": 1.001}
        every, r_every = draw(volume, tf, camera, (40, 40), preintegration=pre, options=fine)
        skipped, r_skipped = draw(volume, tf, camera, (40, 40), preintegration=pre, step=step, options=fine)
        assert r_skipped.last_frame.counters["slice_stride"] == stride
        assert r_skipped.last_frame.counters["slices"] == 1 + math.ceil((len(fac.order) - 1) / stride)
        assert r_skipped.last_frame.counters["samples"] < r_every.last_frame.counters["samples"]
        assert np.abs(skipped - every).max() < (5e-4 if not parallel else 1e-5)


def test_skipped_slices_halve_the_segments_and_stay_near_the_reference():
    """Step 1 (every other slice) on a smooth field: about half the segments, and as a ray caster's
    longer step, a larger error than every slice but within the default's bound."""
    volume = field()
    camera = Camera.orbit(volume.bounds, 30, 20)
    truth = reference_image(volume, SMOOTH_TF, camera, 40, 32)
    for pre in (False, True):
        every, r_every = draw(volume, SMOOTH_TF, camera, preintegration=pre)
        half, r_half = draw(volume, SMOOTH_TF, camera, preintegration=pre, step=1.0)
        ratio = r_half.last_frame.counters["samples"] / r_every.last_frame.counters["samples"]
        assert 0.4 < ratio < 0.6, ratio
        e_every, e_half = image_error(every, truth).rmse, image_error(half, truth).rmse
        assert e_half < 0.01, (e_every, e_half)
        assert not np.array_equal(every, half)


@pytest.mark.parametrize("pre", [False, True])
@pytest.mark.parametrize("step", [0.5, 0.2])
def test_jittered_samples_keep_the_closed_form_of_a_constant_volume(pre, step):
    """Jitter moves the samples, never the length each ray integrates: a constant volume draws the
    closed form with and without it, rays entering and leaving through every face."""
    volume = UniformVolume(np.full((6, 7, 8), 1.0, np.float32), spacing=(0.9, 1.1, 1.0))
    tf = TransferFunction1D.constant(0.3, (0.4, 0.7, 0.2), opacity_unit_distance=0.8)
    for parallel in (False, True):
        camera = Camera.orbit(volume.bounds, 25, 15, zoom=1.3, parallel=parallel)
        expected = oracles.homogeneous_image(oracles.box_path_lengths(camera, 40, 40, volume.bounds),
                                             (0.4, 0.7, 0.2), 0.3, 0.8)  # fmt: skip
        plain, _ = draw(volume, tf, camera, (40, 40), preintegration=pre, step=step)
        jittered, _ = draw(volume, tf, camera, (40, 40), preintegration=pre, step=step, jitter=True)
        assert image_error(jittered, expected).rmse < 0.03
        assert image_error(jittered, plain).rmse < 2e-3


@pytest.mark.parametrize("pre", [False, True])
@pytest.mark.parametrize("shade", [False, True])
def test_jitter_is_seeded_moves_the_samples_and_stays_accurate(pre, shade):
    volume = field()
    camera = Camera.orbit(volume.bounds, 30, 20)
    truth = reference_image(volume, SMOOTH_TF, camera, 40, 32, RenderSettings(shade=shade)) if shade else \
        reference_image(volume, SMOOTH_TF, camera, 40, 32)  # fmt: skip
    plain, _ = draw(volume, SMOOTH_TF, camera, preintegration=pre, shade=shade)
    first, renderer = draw(volume, SMOOTH_TF, camera, preintegration=pre, shade=shade, jitter=True)
    assert np.array_equal(renderer.render(camera, 40, 32), first)  # the same seed, the same image
    other, _ = draw(volume, SMOOTH_TF, camera, preintegration=pre, shade=shade, jitter=True,
                    options={"jitter_seed": 7})  # fmt: skip
    assert not np.array_equal(other, first) and not np.array_equal(first, plain)
    for image in (plain, first, other):
        assert image_error(image, truth).rmse < 0.01


def test_nan_cells_are_transparent_and_the_rest_draws():
    values = np.ones((8, 8, 8), np.float32)
    values[:, :, 5:] = np.nan
    values[2, 2, 2] = np.nan
    volume = UniformVolume(values)
    tf = TransferFunction1D.constant(0.4, (0.3, 0.6, 0.9))
    for mode in ("composite", "maximum", "minimum", "average"):
        image, _ = draw(volume, tf, Camera.orbit(volume.bounds, 30, 20), blend_mode=mode)
        assert image[..., 3].max() > 0.1


@pytest.mark.parametrize("spacing", [(1.0, 1.0, 100.0), (0.01, 1.0, 1.0)])
def test_anisotropic_spacing_up_to_1_to_100(spacing):
    """A stick 100 times longer than wide (a few pixels across: silhouettes dominate the error,
    measured 0.038 and 0.02) and a pancake 100 times flatter than wide."""
    volume = field((5, 16, 16), spacing=spacing)
    camera = Camera.orbit(volume.bounds, 30, 20)
    truth = reference_image(volume, SMOOTH_TF, camera, 32, 32)
    image, _ = draw(volume, SMOOTH_TF, camera, (32, 32), preintegration=True)
    assert image[..., 3].max() > 0.05
    assert image_error(image, truth).rmse < 0.05


def test_an_eye_inside_the_volume_is_refused_in_one_line_under_perspective():
    volume = field()
    inside = Camera(position=(8.0, 7.0, 6.0), focal_point=(8.0, 7.0, 0.0), clipping_range=(0.01, 100.0))
    renderer = ShearWarpRenderer()
    renderer.set_volume(volume)
    renderer.set_transfer_function(SMOOTH_TF)
    with pytest.raises(VolrenError, match="inside") as info:
        renderer.render(inside, 16, 16)
    assert "\n" not in str(info.value)
    image = renderer.render(Camera.orbit(volume.bounds, 30, 20), 16, 16)  # still usable
    assert image[..., 3].max() > 0
    # parallel rays have no eye: the same view draws
    draw(volume, SMOOTH_TF, Camera(position=(8.0, 7.0, 6.0), focal_point=(8.0, 7.0, 0.0), parallel=True,
                                   parallel_scale=10.0, clipping_range=(0.01, 100.0)), (16, 16))  # fmt: skip


@pytest.mark.parametrize("options", [{"oversampling": 0}, {"table_size": 3}, {"lookup": "cubic"},
                                     {"early_termination": "yes"}, {"termination_alpha": 2}, {"nope": 1},
                                     {"downsample": 3}, {"downsample": 2.0}, {"downsample": True},
                                     {"jitter_seed": -1}, {"jitter_seed": 1.5}, {"length_ratio": 1.0},
                                     {"length_ratio": 2}, {"length_ratio": "coarse"}, {"pixels_per_voxel": 0.1},
                                     {"pixels_per_voxel": 2}, {"pixels_per_voxel": "half"}])  # fmt: skip
def test_bad_options_are_one_line_errors(options):
    with pytest.raises(VolrenError) as info:
        ShearWarpRenderer().set_settings(RenderSettings(options=options))
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("pre", [False, True])
@pytest.mark.parametrize("lookup", ["nearest", "bilinear"])
def test_shading_and_lookups_render(pre, lookup):
    volume = field()
    camera = Camera.orbit(volume.bounds, 30, 20)
    plain, _ = draw(volume, SMOOTH_TF, camera, preintegration=pre, options={"lookup": lookup})
    lit, renderer = draw(volume, SMOOTH_TF, camera, preintegration=pre, shade=True, step=0.25,
                         options={"lookup": lookup})  # fmt: skip
    assert np.abs(lit - plain).max() > 0.02
    assert renderer.last_frame.counters["planes_per_slab"] == 2


def test_shading_takes_every_renderers_threshold_on_an_anisotropic_grid(monkeypatch):
    """No shading where |grad s| <= `gradient_threshold` of the value span per characteristic length
    (the smallest spacing), as in the other renderers: not per mean spacing."""
    import volren_shearwarp.renderer as module

    real = module.composite_slabs
    thresholds = []

    def spy(*args, **kwargs):
        thresholds.append(
            inspect.signature(real.py_func).bind(*args, **kwargs).arguments["light"].gradient_threshold
        )
        return real(*args, **kwargs)

    monkeypatch.setattr(module, "composite_slabs", spy)
    volume = field(spacing=(1.0, 0.5, 4.0))
    draw(volume, SMOOTH_TF, Camera.orbit(volume.bounds, 30, 20), shade=True)
    lo, hi = volume.value_range
    assert thresholds and set(thresholds) == {gradient_threshold(hi - lo, volume.characteristic_length)}


def test_a_fast_frame_is_one_block_and_can_still_be_cancelled():
    """Blocks of slices follow the previous frame's time (one parallel launch for a fast frame), and
    the one progress call of such a frame still cancels it."""
    volume = field()
    camera = Camera.orbit(volume.bounds, 30, 20)
    _, renderer = draw(volume, SMOOTH_TF, camera, preintegration=True)
    calls: list[float] = []
    renderer.render(camera, 40, 32, progress=calls.append)
    assert calls == [1.0]

    def cancel(fraction: float) -> None:
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        renderer.render(camera.azimuth(10), 40, 32, progress=cancel)


def test_auto_levels_follow_the_tf_sharpness():
    """Translucent TFs get one intermediate pixel per voxel at least and 128 table entries; sharp ones 2 and 256."""
    translucent = voxel_optical_depth(TransferFunction1D.ramp(0.0, 1.0, 0.2), 1.0)
    opaque = voxel_optical_depth(TransferFunction1D.ramp(0.0, 1.0, 0.95), 1.0)
    assert (auto_oversampling(translucent), auto_table_size(translucent)) == (0.5, 128)
    assert (auto_oversampling(opaque), auto_table_size(opaque)) == (2.0, 256)


# ----------------------------------------------------------------------------- clipping
@pytest.mark.parametrize("parallel", [True, False])
@pytest.mark.parametrize("settings, bound", [
    ({}, 0.01), ({"preintegration": False}, 0.01), ({"step": 0.25}, 0.01), ({"shade": True}, 0.01),
    ({"options": {"lookup": "bilinear", "early_termination": False}}, 0.01),
    # two intermediate pixels per output pixel: the warp's blur of the silhouettes, most of the error
    # above (0.005 parallel, 0.0075 perspective, clipped or not), drops out and what is left is the clipping's
    ({"options": {"oversampling": 2.0}}, 0.002),
])  # fmt: skip
def test_the_near_and_far_planes_cut_a_constant_box_exactly(parallel, settings, bound):
    """Only the part of the box between the planes is drawn: the closed form with the clipped path
    lengths (planes perpendicular to the view direction, at depths along it)."""
    volume, tf, cases = clipped_constant_box(parallel)
    for near, far, clipped, expected in cases:
        image, renderer = draw(volume, tf, clipped, (40, 40), **settings)
        assert renderer.last_frame.counters["clipped"] == 1.0
        assert image_error(image, expected).rmse < bound, (near, far)


@pytest.mark.parametrize("parallel", [True, False])
def test_a_user_camera_whose_far_plane_cuts_the_volume_matches_the_reference(parallel):
    """The bonsai report in small: a camera far up +z with the default clipping range, its far plane
    halfway down the volume; every blend mode against the reference, and the unclipped image differs."""
    volume = field()
    camera = distant_camera_cut_by_far_plane(volume.bounds, 0.45, parallel)
    unclipped = replace(camera, clipping_range=(camera.clipping_range[0], 2 * camera.clipping_range[1]))
    for mode in ("composite", "maximum", "minimum", "average"):
        truth = reference_image(volume, SMOOTH_TF, camera, 40, 32, RenderSettings(blend_mode=mode))
        image, renderer = draw(volume, SMOOTH_TF, camera, blend_mode=mode)
        whole, _ = draw(volume, SMOOTH_TF, unclipped, blend_mode=mode)
        assert renderer.last_frame.counters["clipped"] == 1.0
        if mode != "maximum":  # the maximum lies at the top, in front of the far plane
            assert image_error(whole, truth).rmse > 0.05, mode
        # the projections' error on oblique views is the renderer's own (0.022 unclipped, 0.031 clipped)
        assert image_error(image, truth).rmse < (0.01 if mode == "composite" else 0.04), mode


def test_planes_clear_of_the_volume_keep_the_fast_path_and_the_image():
    """Cameras from `Camera.orbit` (and any whose planes clear the volume) do not clip: same image,
    bit for bit, as with the planes moved further out."""
    volume = field()
    camera = Camera.orbit(volume.bounds, 30, 20)
    near, far = camera.clipping_range
    image, renderer = draw(volume, SMOOTH_TF, camera, preintegration=True)
    assert renderer.last_frame.counters["clipped"] == 0.0
    wider, renderer = draw(
        volume, SMOOTH_TF, replace(camera, clipping_range=(near / 2, far * 2)), preintegration=True
    )
    assert renderer.last_frame.counters["clipped"] == 0.0
    assert np.array_equal(image, wider)


def test_a_new_tf_makes_only_the_lengths_its_frame_needs_and_a_turn_makes_the_batch():
    """Under perspective a frame with a new TF makes the tables of its own segment lengths only (a
    TF drag makes a new TF every frame); the first frame that misses a length, a turning camera's,
    makes every length a turn about the volume needs in one batch, so the next turns wait for none."""
    volume = field((24, 26, 28))
    renderer = ShearWarpRenderer()
    renderer.set_volume(volume)
    renderer.set_settings(RenderSettings(preintegration=True))
    camera = Camera.orbit(volume.bounds, 20.0, 10.0, zoom=2.0)
    for tf in (SMOOTH_TF.copy(), SMOOTH_TF.copy()):
        tf.set_opacity_points([[-1, 0.0], [4, 0.5]])  # a new TF version
        renderer.set_transfer_function(tf)
        renderer.render(camera, 48, 40)
        assert renderer.last_frame is not None
        assert len(renderer._pools["pre"].slots) == renderer.last_frame.counters["table_lengths"] > 1
    made = []
    for azimuth in range(24, 40, 3):
        renderer.render(Camera.orbit(volume.bounds, azimuth, 10.0, zoom=2.0), 48, 40)
        made.append(len(renderer._pools["pre"].slots))
    assert made[0] > 2 * renderer.last_frame.counters["table_lengths"]  # the batch
    assert made[1:] == [made[0]] * (len(made) - 1)  # nothing more while turning


def test_a_coarser_length_grid_makes_fewer_tables_and_stays_near_the_fine_one():
    """`length_ratio` (a TF drag's previews use 1.1): fewer tables per TF under perspective, each
    segment's opacity off by at most (ratio - 1) / 2 of its optical depth; against the exact lengths
    (ratio 1.001) the fine default grid and the coarse one differ by about their ratios' error."""
    volume = field((24, 26, 28))
    camera = Camera.orbit(volume.bounds, 20.0, 10.0, zoom=2.0)
    images, lengths = {}, {}
    for ratio in (1.001, 1.02, 1.1):
        images[ratio], renderer = draw(volume, SMOOTH_TF, camera, (96, 80), preintegration=True,
                                       options={"length_ratio": ratio})  # fmt: skip
        lengths[ratio] = renderer.last_frame.counters["table_lengths"]
    assert lengths[1.001] > lengths[1.02] > lengths[1.1] >= 1
    fine = np.abs(images[1.02] - images[1.001]).max()
    coarse = np.abs(images[1.1] - images[1.001]).max()
    assert 0 < fine < coarse < 0.02  # measured 0.0031 and 0.0104 (alpha up to 1)
