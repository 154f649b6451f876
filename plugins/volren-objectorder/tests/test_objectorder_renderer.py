"""The object-order plugin: the conformance kit, the same samples as a ray caster (a numpy march at
the same positions), the skipping techniques changing nothing they should not, the octree reused
on colour edits, and bad input (thin, constant, NaN, anisotropic volumes, axis and 45 degree views)."""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest
from volren_objectorder import ObjectOrderRenderer

from volren.errors import VolrenError
from volren.kernels.sample_placement import pixel_phases
from volren.model import BlendMode, Camera, RenderSettings, TransferFunction1D, UniformVolume
from volren.model.crop import crop_volume
from volren.testing import conformance_test, image_error, oracles
from volren.testing.reference_images import reference_image
from volren.testing.render_helpers import SHELL_TF, SMOOTH_TF, clipped_constant_box, field, render_checked
from volren.testing.scenes import distant_camera_cut_by_far_plane

# one pytest test per check of the kit
test_conformance = conformance_test(ObjectOrderRenderer, quick=True)

OPAQUE_TF = TransferFunction1D([[-2, 1, 1, 1], [4, 1, 0.4, 0.2]], [[-2, 0.0], [0.3, 1.0]], 1.0)

draw = partial(render_checked, ObjectOrderRenderer)


# ------------------------------------------------------------------- same samples as a ray caster
@pytest.mark.parametrize("parallel", [True, False])
@pytest.mark.parametrize("offsets", ["interleaved", "random"])
def test_the_samples_are_a_ray_casters(parallel, offsets):
    """Object order, octree skipping and all, composites exactly the samples of a ray caster at the
    same step and offsets: the images agree to float precision."""
    volume = field((7, 8, 9), spacing=(1.0, 1.3, 0.8))
    camera = Camera.orbit(volume.bounds, 35, 25, zoom=1.2, parallel=parallel)
    w, h = 20, 16
    image, _ = draw(volume, SHELL_TF, camera, (w, h), step=0.37,
                    options={"depth_offsets": offsets, "jitter_seed": 3, "hidden_volume_removal": False,
                             "classification_table": 0})  # fmt: skip
    expected = oracles.midpoint_march(volume, SHELL_TF, camera, w, h, 0.37, pixel_phases(offsets, w, h, 3))
    assert expected[..., 3].max() > 0.3
    np.testing.assert_allclose(image, expected, atol=2e-6)


def test_the_classification_table_is_close_to_exact():
    """The post-classification table (linear between its entries) against exact classification:
    off by a fraction of the TF's slope times the table's spacing, where a breakpoint falls between
    two entries."""
    volume = field((7, 8, 9))
    camera = Camera.orbit(volume.bounds, 35, 25, parallel=True)
    exact, _ = draw(volume, SHELL_TF, camera, options={"classification_table": 0})
    table, _ = draw(volume, SHELL_TF, camera)
    assert 0 < np.abs(table - exact).max() < 1e-3


# ------------------------------------------------------------------------------ skipping
@pytest.mark.parametrize("parallel", [False, True])
@pytest.mark.parametrize("pre", [False, True])
def test_octree_skipping_changes_no_pixel(parallel, pre):
    volume = field((16, 16, 16))
    camera = Camera.orbit(volume.bounds, 35, 25, parallel=parallel)
    common = {"hidden_volume_removal": False}
    on, r_on = draw(volume, SHELL_TF, camera, preintegration=pre, options={**common, "octree_skipping": True})
    off, r_off = draw(
        volume, SHELL_TF, camera, preintegration=pre, options={**common, "octree_skipping": False}
    )
    assert r_on.last_frame.counters["cells"] < 0.8 * r_off.last_frame.counters["cells"]
    if pre:  # a segment that starts in a skipped cell fetches its front sample: rounding only
        np.testing.assert_allclose(on, off, atol=1e-6)
    else:
        np.testing.assert_array_equal(on, off)


@pytest.mark.parametrize("parallel", [False, True])
@pytest.mark.parametrize("settings", [
    {},
    {"preintegration": True},
    {"shade": True},
    {"shade": True, "preintegration": True},
    {"blend_mode": BlendMode.MAXIMUM},
    {"blend_mode": BlendMode.MINIMUM},
    {"blend_mode": BlendMode.AVERAGE},
])  # fmt: skip
def test_blocks_of_cells_draw_the_cells_image(parallel, settings):
    # an odd number of cells along x and z (blocks one cell thick at the far side), a NaN corner, a TF
    # that leaves some cells of a block transparent, hidden volume removal off so that every node
    # above the cells goes one way or the other: as blocks, or cell by cell (block_pixels 0)
    volume = field((14, 16, 18))
    values = volume.values.copy()
    values[7, 8, 9] = np.nan
    volume = UniformVolume(values)
    camera = Camera.orbit(volume.bounds, 35, 25, parallel=parallel)
    common = {"hidden_volume_removal": False}
    blocks, r_blocks = draw(
        volume, SHELL_TF, camera, (64, 48), **settings, options={**common, "block_pixels": 4096}
    )
    cells, r_cells = draw(
        volume, SHELL_TF, camera, (64, 48), **settings, options={**common, "block_pixels": 0}
    )
    c_blocks, c_cells = r_blocks.last_frame.counters, r_cells.last_frame.counters
    if settings.get("blend_mode", BlendMode.COMPOSITE) == BlendMode.COMPOSITE:
        assert c_blocks["nodes"] < 0.5 * c_cells["nodes"]  # the leaf cells were not visited one by one
    else:  # blocks composite only
        assert c_blocks["nodes"] == c_cells["nodes"]
    assert c_blocks["samples"] == c_cells["samples"]
    np.testing.assert_allclose(blocks, cells, atol=2e-6)
    assert np.abs(blocks - cells).max() < np.abs(cells).max() * 1e-5 + 1e-12


def _views(volume, parallel):
    """Cameras whose rays run every way along some axis and one way along others: oblique, from
    below, along an axis, from inside (perspective), and with the far plane through the volume."""
    cams = [Camera.orbit(volume.bounds, az, el, zoom=1.1, parallel=parallel)
            for az, el in ((35, 25), (-120, -40), (0, 0), (90, 0), (200, 70))]  # fmt: skip
    cams.append(distant_camera_cut_by_far_plane(volume.bounds, 0.45, parallel))
    if not parallel:
        cams.append(Camera(position=(6.0, 5.0, 4.0), focal_point=(13.0, 1.0, 9.0), view_angle=70.0))
    return cams


# a band of opacity just under the top face (z), where rays that leave through it end their last
# piece, and one around the middle: segments run out of both into cells that are transparent
TOP_TF = TransferFunction1D(
    [[-2, 1, 0.5, 0.2], [4, 0.3, 0.6, 1.0]], [[1.2, 0.0], [1.5, 0.8], [1.8, 0.0], [2.5, 0.0], [2.8, 0.9]], 1.0
)


@pytest.mark.parametrize("parallel", [False, True])
def test_one_sided_dilation_skips_cells_and_changes_no_pixel(parallel):
    """Pre-integrated, the octree dilates each cell's range toward the eye only (the back end of the
    rim both ways): every view draws what skipping nothing draws, and an oblique one classifies
    fewer cells visible than the box both ways would."""
    from volren_objectorder.octree import Reach

    volume = field((12, 13, 14), spacing=(1.0, 0.8, 1.2))
    # and scattered voxels, some on the faces, that only a spike of the TF sees: a ray's last
    # piece then often ends on a visible point of a face outside its last sample's cell
    spots = (np.random.default_rng(5).random((12, 13, 14)) < 0.03).astype(np.float32)
    spike = TransferFunction1D(
        [[0, 1, 0.5, 0.2], [1, 0.3, 0.6, 1.0]], [[0.0, 0.0], [0.05, 0.0], [0.5, 1.0]], 0.5
    )
    options = {"hidden_volume_removal": False}
    for vol, tf in ((volume, TOP_TF), (UniformVolume(spots, spacing=(1.0, 0.8, 1.2)), spike)):
        for camera in _views(vol, parallel):
            on, _ = draw(vol, tf, camera, (36, 30), preintegration=True, step=0.7, options=options)
            off, _ = draw(vol, tf, camera, (36, 30), preintegration=True, step=0.7,
                          options={**options, "octree_skipping": False})  # fmt: skip
            assert on[..., 3].max() > 0.02
            np.testing.assert_allclose(on, off, atol=1e-6, err_msg=str(camera))
    camera = _views(volume, parallel)[0]
    _, r = draw(volume, TOP_TF, camera, (36, 30), preintegration=True, step=0.7)
    one_sided = r.last_frame.counters["cells_visible"]
    both = r.octree.classify(TOP_TF, Reach.both_ways((1, 1, 1))).visible_cells
    assert one_sided < 0.95 * both


def test_the_reach_is_one_sided_only_where_it_is_cheap_and_exact():
    """One-sided along axes whose rays all run one way, with a rim at the faces they leave through;
    both ways everywhere when a step spans more than a cell (the rim's boxes would grow with the
    step cubed) or the far plane cuts the volume."""
    from volren_objectorder.octree import Reach
    from volren_objectorder.patterns import ray_table
    from volren_objectorder.renderer import segment_reach

    def reach(volume, camera, step):
        h = step * volume.characteristic_length
        rays = ray_table(camera, volume, 24, 20, h, pixel_phases("interleaved", 24, 20, 0))
        return segment_reach(camera, volume, rays, h)

    volume = field((10, 11, 12))
    oblique = reach(volume, Camera.orbit(volume.bounds, 35, 25, parallel=True), 0.5)
    assert oblique != Reach.both_ways((1, 1, 1)) and all(sum(w) == 1 for w in oblique.window)
    assert all(sum(r) == 2 for r in oblique.rim)  # the rim on the face each axis's rays leave through
    flat = UniformVolume(volume.values, spacing=(1.0, 1.0, 0.01))
    # step 2 (in the smallest spacing) spans two cells along z
    assert reach(flat, Camera.orbit(flat.bounds, 35, 25, parallel=True), 2.0) == Reach.both_ways(
        tuple(int(np.ceil(2.0 * flat.characteristic_length / s - 1e-9)) for s in flat.spacing)
    )
    far = reach(volume, distant_camera_cut_by_far_plane(volume.bounds, 0.45, True), 0.5)
    assert far == Reach.both_ways((1, 1, 1))


@pytest.mark.parametrize("parallel", [False, True])
def test_the_ray_table_holds_the_cameras_pixel_rays(parallel):
    """Each pixel's ray against `Camera.pixel_rays` in float64: origin, direction (one shared row
    under a parallel projection) and where it enters the box; then a renderer switching projection
    draws what a fresh one does (the table's arrays change shape with it)."""
    from volren_objectorder.patterns import ray_table

    volume = field((10, 11, 12), spacing=(1.0, 0.8, 1.3))
    camera = Camera.orbit(volume.bounds, 35, 25, parallel=parallel)
    width, height = 24, 20
    rays = ray_table(camera, volume, width, height, 0.5, pixel_phases("interleaved", width, height, 0))
    near, directions = camera.pixel_rays(width, height)
    near, directions = near.reshape(-1, 3), directions.reshape(-1, 3)
    spacing, origin = np.asarray(volume.spacing), np.asarray(volume.origin)
    assert rays.direction.shape == ((1, 3) if parallel else (width * height, 3))
    np.testing.assert_allclose(rays.origin, (near - origin) / spacing, atol=1e-9)
    np.testing.assert_allclose(np.broadcast_to(rays.world_direction, directions.shape), directions, atol=1e-9)
    np.testing.assert_allclose(
        np.broadcast_to(rays.direction, directions.shape), directions / spacing, atol=1e-9
    )
    np.testing.assert_allclose(rays.inverse * rays.direction, 1.0, atol=1e-12)
    upper = (np.asarray(volume.dimensions) - 1.0) * spacing
    with np.errstate(divide="ignore"):
        ta, tb = (0.0 - (near - origin)) / directions, (upper - (near - origin)) / directions
    t_in = np.maximum(np.minimum(ta, tb).max(axis=1), 0.0)
    hit = rays.count > 0
    assert hit.sum() > 0.2 * width * height and not hit.all()
    np.testing.assert_allclose(rays.t0[hit], t_in[hit], atol=1e-9)

    tf = SHELL_TF
    other = Camera.orbit(volume.bounds, 35, 25, parallel=not parallel)
    switched = ObjectOrderRenderer()
    switched.set_volume(volume)
    switched.set_transfer_function(tf)
    switched.render(camera, width, height)
    fresh, _ = draw(volume, tf, other, (width, height))
    np.testing.assert_array_equal(switched.render(other, width, height), fresh)


@pytest.mark.parametrize("parallel", [False, True])
def test_hidden_volume_removal_skips_cells_and_changes_little(parallel):
    volume = field((24, 24, 24))
    camera = Camera.orbit(volume.bounds, 30, 20, parallel=parallel)
    term = 0.98
    on, r_on = draw(volume, OPAQUE_TF, camera, (48, 48), options={"termination_alpha": term})
    off, r_off = draw(volume, OPAQUE_TF, camera, (48, 48), options={"hidden_volume_removal": False})
    c_on, c_off = r_on.last_frame.counters, r_off.last_frame.counters
    assert c_on["cells_occluded"] > 0 and c_on["occluded_ratio"] > 0.3
    assert c_on["cells"] < c_off["cells"] and c_on["samples"] < c_off["samples"]
    assert c_off["cells_occluded"] == 0
    assert np.abs(on - off).max() <= 1 - term + 1e-6


def test_a_colour_edit_reuses_the_octree_and_an_opacity_edit_reclassifies_it():
    volume = field()
    tf = SHELL_TF.copy()
    camera = Camera.orbit(volume.bounds, 30, 20, parallel=True)
    renderer = ObjectOrderRenderer()
    renderer.set_volume(volume)
    renderer.set_transfer_function(tf)
    renderer.set_settings(RenderSettings(options={"hidden_volume_removal": False}))
    renderer.render(camera, 24, 24)
    octree = renderer.octree
    (first,) = octree._cache.values()
    before = renderer.last_frame.counters["cells"]
    tf.set_color_points([[-2, 0.0, 1.0, 0.0], [4, 1.0, 0.0, 1.0]])
    renderer.render(camera, 24, 24)
    assert renderer.octree is octree and list(octree._cache.values()) == [first]  # nothing rebuilt or redone
    tf.set_opacity_points([[2.5, 0.0], [4, 0.6]])
    renderer.render(camera, 24, 24)
    assert renderer.octree is octree and len(octree._cache) == 2
    assert renderer.last_frame.counters["cells"] != before


# ------------------------------------------------------------------------------ accuracy
@pytest.mark.parametrize("parallel", [False, True])
def test_a_smooth_tf_matches_the_reference_shaded_and_preintegrated(parallel):
    volume = field()
    camera = Camera.orbit(volume.bounds, 30, 20, parallel=parallel)
    for settings in ({}, {"preintegration": True}, {"shade": True}, {"shade": True, "preintegration": True}):
        truth = reference_image(volume, SMOOTH_TF, camera, 40, 32, RenderSettings(**settings))
        image, _ = draw(volume, SMOOTH_TF, camera, **settings)
        assert image_error(image, truth).rmse < 0.01, settings


def test_preintegration_beats_post_classification_on_a_spiky_tf():
    volume = field((12, 12, 12))
    spiky = TransferFunction1D([[-2, 0.9, 0.9, 0.2], [4, 0.2, 0.6, 1.0]],
                               [[0.9, 0.0], [1.0, 0.9], [1.1, 0.0]], opacity_unit_distance=1.0)  # fmt: skip
    camera = Camera.orbit(volume.bounds, 30, 20, zoom=1.2)
    truth = reference_image(volume, spiky, camera, 48, 48)
    pre, _ = draw(volume, spiky, camera, (48, 48), preintegration=True, step=1.0)
    post, _ = draw(volume, spiky, camera, (48, 48), preintegration=False, step=1.0)
    assert 3 * image_error(pre, truth).rmse <= image_error(post, truth).rmse


# ----------------------------------------------------------------------------- bad input
def test_a_grid_two_samples_thick_renders_along_every_axis():
    for shape in [(2, 9, 9), (9, 2, 9), (9, 9, 2)]:
        volume = UniformVolume(np.random.default_rng(1).random(shape).astype(np.float32))
        tf = TransferFunction1D([[0, 1, 0.5, 0.2]], [[0, 0.2], [1, 0.9]], 0.3)
        for parallel in (False, True):
            for pre in (False, True):
                image, _ = draw(
                    volume, tf, Camera.orbit(volume.bounds, 30, 20, parallel=parallel), preintegration=pre
                )
                assert image[..., 3].max() > 0


def test_a_constant_volume_draws_the_closed_form():
    volume = UniformVolume(np.full((6, 7, 8), 1.0, np.float32), spacing=(0.9, 1.1, 1.0))
    tf = TransferFunction1D.constant(0.3, (0.4, 0.7, 0.2), opacity_unit_distance=0.8)
    for parallel in (False, True):
        camera = Camera.orbit(volume.bounds, 25, 15, zoom=1.3, parallel=parallel)
        expected = oracles.homogeneous_image(oracles.box_path_lengths(camera, 40, 40, volume.bounds),
                                             (0.4, 0.7, 0.2), 0.3, 0.8)  # fmt: skip
        for pre in (False, True):
            image, _ = draw(volume, tf, camera, (40, 40), preintegration=pre)
            assert image_error(image, expected).rmse < 1e-4


def test_nan_cells_are_transparent_and_the_rest_draws():
    values = np.ones((8, 8, 8), np.float32)
    values[:, :, 5:] = np.nan
    values[2, 2, 2] = np.nan
    volume = UniformVolume(values)
    tf = TransferFunction1D.constant(0.4, (0.3, 0.6, 0.9))
    for mode in ("composite", "maximum", "minimum", "average"):
        for pre in (False, True) if mode == "composite" else (False,):
            image, _ = draw(
                volume, tf, Camera.orbit(volume.bounds, 30, 20), blend_mode=mode, preintegration=pre
            )
            assert image[..., 3].max() > 0.1


@pytest.mark.parametrize("spacing", [(1.0, 1.0, 100.0), (0.01, 1.0, 1.0)])
def test_anisotropic_spacing_up_to_1_to_100(spacing):
    volume = field((5, 16, 16), spacing=spacing)
    camera = Camera.orbit(volume.bounds, 30, 20)
    truth = reference_image(volume, SMOOTH_TF, camera, 32, 32)
    for pre in (False, True):
        image, _ = draw(volume, SMOOTH_TF, camera, (32, 32), preintegration=pre)
        assert image[..., 3].max() > 0.05
        assert image_error(image, truth).rmse < 0.02


@pytest.mark.parametrize("azimuth, elevation", [(0, 0), (90, 0), (0, 90), (45, 0), (45, 35.26), (180, 0)])
@pytest.mark.parametrize("parallel", [False, True])
def test_axis_and_diagonal_views_match_the_reference(azimuth, elevation, parallel):
    """Rays along grid planes (axis views) and through cell edges and corners (45 degrees)."""
    volume = field((9, 10, 11))
    camera = Camera.orbit(volume.bounds, azimuth, elevation, parallel=parallel)
    truth = reference_image(volume, SMOOTH_TF, camera, 24, 24)
    image, _ = draw(volume, SMOOTH_TF, camera, (24, 24))
    assert image_error(image, truth).rmse < 0.01


def test_a_cropped_volume_renders_its_part():
    volume = field()
    cropped = crop_volume(volume, (2.0, 9.5, 0.0, 15.0, 3.0, 12.0))
    camera = Camera.orbit(volume.bounds, 30, 20)
    image, _ = draw(cropped, SMOOTH_TF, camera, (32, 32))
    truth = reference_image(cropped, SMOOTH_TF, camera, 32, 32)
    assert image_error(image, truth).rmse < 0.01


@pytest.mark.parametrize("options", [{"octree_skipping": 1}, {"hidden_volume_removal": "no"}, {"termination_alpha": 2},
                                     {"depth_offsets": "halton"}, {"jitter_seed": -1}, {"table_size": 3},
                                     {"band_rows": 0}, {"classification_table": 8}, {"block_pixels": -1}, {"nope": 1}])  # fmt: skip
def test_bad_options_are_one_line_errors(options):
    with pytest.raises(VolrenError) as info:
        ObjectOrderRenderer().set_settings(RenderSettings(options=options))
    assert "\n" not in str(info.value)


# ----------------------------------------------------------------------------- clipping
@pytest.mark.parametrize("parallel", [True, False])
@pytest.mark.parametrize("settings", [{}, {"preintegration": True}, {"step": 0.25, "shade": True},
                                      {"options": {"hidden_volume_removal": False,
                                                   "classification_table": 0}}])  # fmt: skip
def test_the_near_and_far_planes_cut_a_constant_box_exactly(parallel, settings):
    """Only the part of the box between the planes is drawn (rays start on the near plane and end on
    the far one): the closed form with the clipped path lengths, to float precision."""
    volume, tf, cases = clipped_constant_box(parallel)
    for near, far, clipped, expected in cases:
        image, _ = draw(volume, tf, clipped, (40, 40), **settings)
        assert image_error(image, expected).rmse < 1e-5, (near, far)


@pytest.mark.parametrize("parallel", [True, False])
def test_a_user_camera_whose_far_plane_cuts_the_volume_matches_the_reference(parallel):
    """A camera far out with the default clipping range, its far plane halfway through the volume:
    every blend mode against the reference, and the unclipped image differs."""
    volume = field()
    camera = distant_camera_cut_by_far_plane(volume.bounds, 0.45, parallel)
    unclipped = Camera(**{**camera.to_dict(), "clipping_range": (0.01, 2000.0)})
    for mode in ("composite", "maximum", "minimum", "average"):
        truth = reference_image(volume, SMOOTH_TF, camera, 40, 32, RenderSettings(blend_mode=mode))
        image, _ = draw(volume, SMOOTH_TF, camera, blend_mode=mode)
        whole, _ = draw(volume, SMOOTH_TF, unclipped, blend_mode=mode)
        if mode != "maximum":  # the maximum lies at the top, in front of the far plane
            assert image_error(whole, truth).rmse > 0.05, mode
        assert image_error(image, truth).rmse < 0.01, mode


@pytest.mark.parametrize("window", [((1, 1), (1, 1), (1, 1)), ((2, 0), (0, 0), (0, 3)), ((0, 0),) * 3, ((5, 5),) * 3,
                                    ((0, 1), (2, 1), (1, 0))])  # fmt: skip
@pytest.mark.parametrize("shape", [(5, 6, 7), (1, 3, 9), (17, 2, 4)])
def test_the_dilated_ranges_are_the_min_and_max_over_each_box(shape, window):
    """`_dilate` against brute force: every element's box from `below` to `above` cells along each
    axis (clipped to the grid)."""
    from volren_objectorder.octree import _dilate

    a = np.random.default_rng(sum(shape)).random(shape).astype(np.float32)
    (bx, ax), (by, ay), (bz, az) = window
    for take_max, reduce in ((True, np.max), (False, np.min)):
        got = _dilate(a, window, take_max)
        for k, j, i in np.ndindex(shape):
            box = a[max(k - bz, 0) : k + az + 1, max(j - by, 0) : j + ay + 1, max(i - bx, 0) : i + ax + 1]
            assert got[k, j, i] == reduce(box)
