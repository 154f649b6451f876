"""The `raycast` renderer: a ray caster's samples exactly, skipping that changes no pixel, the
distance jumps, pre-integration, the projections and bad options."""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest

from volren.errors import VolrenError
from volren.kernels.sample_placement import pixel_phases
from volren.model import BlendMode, Camera, RenderSettings, TransferFunction1D, UniformVolume
from volren.renderers.raycast import RaycastRenderer
from volren.renderers.raycast.occupancy import empty_distance
from volren.testing import image_error, oracles
from volren.testing.reference_images import reference_image
from volren.testing.render_helpers import SHELL_TF, SMOOTH_TF, field, render_checked

from .raycast_backends import use_backend

SPIKE_TF = TransferFunction1D(
    [[-2, 1, 0.6, 0.2], [4, 0.2, 0.6, 1.0]], [[1.50, 0.0], [1.52, 1.0], [1.54, 0.0]], 0.5
)

draw = partial(render_checked, RaycastRenderer)


@pytest.mark.parametrize("parallel", [True, False])
@pytest.mark.parametrize("offsets", ["interleaved", "midpoint"])
def test_the_samples_are_a_plain_ray_casters(parallel, offsets):
    """Brick skipping, distance jumps and the classification table included, the image is a plain
    float64 ray caster's at the same step and phases (to the table's interpolation)."""
    volume = field((9, 10, 11), spacing=(1.0, 1.3, 0.8))
    camera = Camera.orbit(volume.bounds, 35, 25, zoom=1.2, parallel=parallel)
    w, h = 24, 20
    image, renderer = draw(volume, SHELL_TF, camera, (w, h), step=0.37,
                           options={"depth_offsets": offsets, "brick_size": 2, "classification_table": 65536})  # fmt: skip
    expected = oracles.midpoint_march(volume, SHELL_TF, camera, w, h, 0.37, pixel_phases(offsets, w, h, 0))
    assert expected[..., 3].max() > 0.3
    np.testing.assert_allclose(image, expected, atol=2e-4)
    assert renderer.last_frame.counters["bricks_empty"] > 0


@pytest.mark.parametrize("parallel", [True, False])
@pytest.mark.parametrize(("pre", "step"), [(False, 0.5), (True, 0.5), (True, 1.3)])
@pytest.mark.parametrize("brick", [1, 2, 4])
def test_skipping_changes_no_pixel(parallel, pre, step, brick):
    """Skipping empty bricks (and jumping out of empty boxes) leaves every pixel as it is without;
    pre-integrated, bricks are widened by the cells a segment reaches (2 cells at step 1.3)."""
    volume = field((20, 22, 24))
    camera = Camera.orbit(volume.bounds, 50, -20, zoom=1.1, parallel=parallel)
    common = {"step": step, "preintegration": pre}
    on, r_on = draw(volume, SHELL_TF, camera, **common, options={"brick_size": brick})
    off, r_off = draw(
        volume, SHELL_TF, camera, **common, options={"brick_size": brick, "empty_space_skipping": False}
    )
    assert on[..., 3].max() > 0.3
    np.testing.assert_allclose(on, off, atol=1e-6)
    assert r_on.last_frame.counters["bricks_empty"] > 0
    assert r_on.last_frame.counters["samples"] < r_off.last_frame.counters["samples"]


@pytest.mark.parametrize("pre", [False, True])
def test_skipping_is_exact_where_data_values_sit_on_a_peaks_foot(pre):
    """Voxels exactly at the value where a TF peak starts (opacity 0 there) make a brick transparent
    for the TF, but the classification table gives such a value the interpolation of the entries
    either side of it, a little opacity: bricks are classified over ranges widened by one entry, so
    skipping stays exact (found by `volren bench skip` on bonsai's spiky TF, 1.3e-2 before)."""
    z, y, x = np.mgrid[0:24, 0:22, 0:20]
    blob = np.exp(-((x - 10) ** 2 + (y - 11) ** 2 + (z - 12) ** 2) / 20.0)
    values = np.where(blob > 0.05, 41 + np.round(blob * 12), 41)  # a plateau at 41 ...
    values = np.where(x < 5, 0, values).astype(np.uint8)  # ... and a background of 0, truly empty
    tf = TransferFunction1D([[0, 1, 0.6, 0.2], [255, 0.2, 0.6, 1.0]],
                            [[0, 0.0], [41, 0.0], [43, 0.7], [45, 0.7], [47, 0.0], [255, 0.0]], 1.0)  # fmt: skip
    volume = UniformVolume(values)
    camera = Camera.orbit(volume.bounds, 40, 25, zoom=1.1)
    options = {"brick_size": 2}
    on, r_on = draw(volume, tf, camera, step=0.5, preintegration=pre, options=options)
    off, _ = draw(
        volume, tf, camera, step=0.5, preintegration=pre, options={**options, "empty_space_skipping": False}
    )
    assert on[..., 3].max() > 0.3 and r_on.last_frame.counters["bricks_empty"] > 0
    faint = (off[..., 3] > 0.0) & (off[..., 3] < 0.05)  # the plateau: not quite transparent in the table
    assert faint.any()
    np.testing.assert_allclose(on, off, atol=1e-6)


def test_an_8_bit_volume_draws_as_its_float_copy():
    """8-bit volumes are kept 8-bit (a quarter of the memory); differences of neighbouring voxels
    must not wrap around."""
    z, y, x = np.mgrid[0:12, 0:13, 0:14]
    values = ((np.sin(x / 2.0) * np.cos(y / 3.0) + z / 12.0) * 120 + 100).clip(0, 255).astype(np.uint8)
    tf = TransferFunction1D(
        [[0, 1, 0.5, 0.2], [255, 0.3, 0.6, 1.0]], [[60, 0.0], [120, 0.8], [200, 0.1]], 2.0
    )
    camera = Camera.orbit((0, 13, 0, 12, 0, 11), 30, 20)
    eight, renderer = draw(UniformVolume(values), tf, camera, step=0.5)
    wide, _ = draw(UniformVolume(values.astype(np.float32)), tf, camera, step=0.5)
    assert renderer._values is not None and renderer._values.dtype == np.uint8
    assert eight[..., 3].max() > 0.3
    np.testing.assert_allclose(eight, wide, atol=1e-6)


def test_an_empty_box_is_left_in_one_jump():
    """A thin shell of visible values in a large transparent grid: rays jump over the empty boxes."""
    z, y, x = np.mgrid[0:48, 0:48, 0:48]
    values = np.where((abs(x - 24) < 2) & (abs(y - 24) < 2) & (abs(z - 24) < 2), 1.0, 0.0).astype(np.float32)
    volume = UniformVolume(values)
    tf = TransferFunction1D([[0, 1, 1, 1], [1, 1, 1, 1]], [[0.4, 0.0], [1.0, 0.8]], 1.0)
    camera = Camera.orbit(volume.bounds, 20, 10, zoom=1.0, parallel=True)
    image, renderer = draw(volume, tf, camera, (32, 32), step=0.5)
    counters = renderer.last_frame.counters
    assert image[..., 3].max() > 0.2
    assert counters["jumps"] > 0
    off, r_off = draw(volume, tf, camera, (32, 32), step=0.5, options={"empty_space_skipping": False})
    np.testing.assert_allclose(image, off, atol=1e-6)
    assert counters["samples"] < 0.2 * r_off.last_frame.counters["samples"]


@pytest.mark.parametrize("shape", [(1, 1, 1), (3, 1, 2), (5, 4, 1), (9, 9, 9), (20, 3, 7)])
def test_the_empty_distance_is_the_chebyshev_distance_to_a_visible_brick(shape):
    rng = np.random.default_rng(sum(shape))
    visible = rng.random(shape) < 0.08
    distance = empty_distance(visible, cap=5)
    points = np.argwhere(visible)
    for idx in np.ndindex(shape):
        if visible[idx]:
            assert distance[idx] == 0
            continue
        nearest = np.abs(points - np.array(idx)).max(axis=1).min() if len(points) else np.inf
        assert distance[idx] == min(nearest, 5), idx


def test_the_empty_distance_fits_a_byte_and_refuses_a_cap_that_does_not():
    visible = np.zeros((3, 4, 5), bool)
    visible[0, 0, 0] = True
    distance = empty_distance(visible, cap=127)
    assert distance.dtype == np.int8 and distance.max() == 4  # the far corner, 4 bricks along x
    with pytest.raises(ValueError, match="127"):
        empty_distance(np.zeros((3, 4, 5), bool), cap=128)


def test_preintegration_beats_post_classification_on_a_spiky_tf():
    volume = field((12, 14, 16))
    camera = Camera.orbit(volume.bounds, 30, 20, zoom=1.2)
    ref = reference_image(volume, SPIKE_TF, camera, 40, 32)
    post, _ = draw(volume, SPIKE_TF, camera, step=1.0)
    pre, _ = draw(volume, SPIKE_TF, camera, step=1.0, preintegration=True, options={"table_size": 1024})
    assert ref[..., 3].max() > 0.2
    assert image_error(pre, ref).rmse < 0.5 * image_error(post, ref).rmse


@pytest.mark.parametrize("parallel", [True, False])
def test_a_smooth_tf_matches_the_reference(parallel):
    volume = field()
    camera = Camera.orbit(volume.bounds, 25, 35, zoom=1.2, parallel=parallel)
    ref = reference_image(volume, SMOOTH_TF, camera, 40, 32)
    for pre in (False, True):
        image, _ = draw(volume, SMOOTH_TF, camera, step=0.25, preintegration=pre)
        assert image_error(image, ref).rmse < 0.003


@pytest.mark.parametrize("mode", [BlendMode.MAXIMUM, BlendMode.MINIMUM, BlendMode.AVERAGE])
def test_the_projections_match_the_reference(mode):
    volume = field((10, 12, 14))
    camera = Camera.orbit(volume.bounds, 30, 20, zoom=1.2)
    ref = reference_image(volume, SMOOTH_TF, camera, 40, 32, RenderSettings(blend_mode=mode))
    image, _ = draw(volume, SMOOTH_TF, camera, step=0.25, blend_mode=mode)
    assert ref[..., 3].max() > 0.1
    assert image_error(image, ref).rmse < 0.01


def test_a_colour_edit_keeps_the_brick_distances_and_an_opacity_edit_recomputes_them():
    volume = field()
    camera = Camera.orbit(volume.bounds, 30, 20)
    _, renderer = draw(volume, SHELL_TF, camera)
    distances = renderer._empty[1]
    recoloured = TransferFunction1D([[-2, 0, 1, 0], [4, 1, 0, 1]], SHELL_TF.opacity_points, 1.0)
    renderer.set_transfer_function(recoloured)
    renderer.render(camera, 40, 32)
    assert renderer._empty[1] is distances
    renderer.set_transfer_function(SMOOTH_TF)
    renderer.render(camera, 40, 32)
    assert renderer._empty[1] is not distances


@pytest.mark.parametrize("spacing", [(1.0, 1.0, 100.0), (0.01, 1.0, 1.0)])
def test_extreme_anisotropy_matches_the_reference(spacing):
    volume = field((6, 7, 8), spacing=spacing)
    camera = Camera.orbit(volume.bounds, 40, 30, zoom=1.2)
    ref = reference_image(volume, SMOOTH_TF, camera, 32, 24)
    image, _ = draw(volume, SMOOTH_TF, camera, (32, 24), step=0.25)
    assert image_error(image, ref).rmse < 0.01


@pytest.mark.parametrize("axis", range(3))
def test_a_grid_one_cell_thick_renders_along_every_axis(axis):
    shape = [6, 7, 8]
    shape[2 - axis] = 2
    volume = field(tuple(shape))
    for azimuth, elevation in ((0, 0), (90, 0), (0, 89)):
        camera = Camera.orbit(volume.bounds, azimuth, elevation, zoom=1.2)
        ref = reference_image(volume, SMOOTH_TF, camera, 32, 24)
        image, _ = draw(volume, SMOOTH_TF, camera, (32, 24), step=0.25)
        assert image_error(image, ref).rmse < 0.01


@pytest.mark.parametrize("options", [{"brick_size": 0}, {"termination_alpha": 0.2}, {"depth_offsets": "random"},
                                     {"table_size": 8}, {"empty_space_skipping": 1}, {"nope": 1},
                                     {"image_stride": 3}, {"image_stride": 128}, {"refine_tolerance": 2.0},
                                     {"refine_tolerance": True}])  # fmt: skip
def test_bad_options_are_one_line_errors(options):
    renderer = RaycastRenderer()
    with pytest.raises(VolrenError) as err:
        renderer.set_settings(RenderSettings(options=options))
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("backend", ["numba", "c"])
@pytest.mark.parametrize("pre", [False, True])
def test_rays_for_listed_pixels_are_the_tiles_rays(pre, backend, monkeypatch):
    """`march_pixels` (what adaptive refinement casts) draws each listed pixel exactly as the tiled
    march does, in any order, in numba and in C."""
    module = use_backend(backend, monkeypatch)
    volume = field()
    camera = Camera.orbit(volume.bounds, 30, 20, zoom=1.2, parallel=False)
    w, h = 40, 32
    full, renderer = draw(volume, SHELL_TF, camera, (w, h), preintegration=pre)
    calls = []
    real = module.march_pixels

    def spy(*args):
        calls.append(args)
        return real(*args)

    monkeypatch.setattr(module, "march_pixels", spy)
    refined, _ = draw(volume, SHELL_TF, camera, (w, h), preintegration=pre,
                      options={"image_stride": 4, "refine_tolerance": 0.0})  # fmt: skip
    assert calls
    *inputs, pixels, out, counts = calls[0]
    picked = np.random.default_rng(1).permutation(w * h)[:200]
    rgba = np.empty((200, 4), np.float32)
    real(*inputs, picked, rgba, np.zeros((200, 4), np.int64))
    np.testing.assert_array_equal(np.minimum(rgba[:, :3], rgba[:, 3:]), full.reshape(-1, 4)[picked, :3])
    np.testing.assert_array_equal(rgba[:, 3], full.reshape(-1, 4)[picked, 3])


def test_adaptive_refinement_casts_fewer_rays_near_the_full_image():
    """Where the image is smooth, refinement casts a fraction of the rays and interpolates the rest
    close to the full image; silhouettes are cast to the pixel; a lower tolerance casts more."""
    z, y, x = np.mgrid[0:16, 0:16, 0:16]
    volume = UniformVolume((np.sin(x / 6.0) + y / 12.0 + z / 10.0).astype(np.float32))
    camera = Camera.orbit(volume.bounds, 25, 35, zoom=1.2)
    w, h = 96, 80
    full, _ = draw(volume, SMOOTH_TF, camera, (w, h))
    refined, renderer = draw(
        volume, SMOOTH_TF, camera, (w, h), options={"image_stride": 8, "refine_tolerance": 0.05}
    )
    rays = renderer.last_frame.counters["rays_cast"]
    assert rays < 0.5 * w * h
    err = image_error(refined, full)
    assert err.rmse < 2e-3 and err.max_abs < 0.03
    np.testing.assert_array_equal(refined[..., 3] > 0, full[..., 3] > 0)
    finer, renderer = draw(
        volume, SMOOTH_TF, camera, (w, h), options={"image_stride": 8, "refine_tolerance": 0.01}
    )
    assert renderer.last_frame.counters["rays_cast"] > rays
    assert image_error(finer, full).rmse < 0.2 * err.rmse


@pytest.mark.parametrize("backend", ["numba", "c"])
@pytest.mark.parametrize("parallel", [False, True])
def test_the_counters_account_for_every_segment(backend, parallel, monkeypatch):
    """Post-classified with no early termination, every segment of every ray is sampled or skipped:
    skipping on, samples + segments skipped is the sample count with skipping off (where none is
    skipped); each ray that stops early is counted, and only those."""
    module = use_backend(backend, monkeypatch)
    volume = field((20, 22, 24))
    camera = Camera.orbit(volume.bounds, 50, -20, zoom=1.1, parallel=parallel)
    never = {"termination_alpha": 1.0}
    _, on = draw(volume, SHELL_TF, camera, step=0.5, options={**never, "brick_size": 2})
    _, off = draw(
        volume, SHELL_TF, camera, step=0.5, options={**never, "brick_size": 2, "empty_space_skipping": False}
    )
    c_on, c_off = on.last_frame.counters, off.last_frame.counters
    assert c_off["segments_skipped"] == 0 and c_on["segments_skipped"] > 0
    assert c_on["samples"] + c_on["segments_skipped"] == c_off["samples"]
    assert c_on["rays_terminated"] == c_off["rays_terminated"] == 0
    # each pixel's ray alone (`march_pixels`, on the frame's own inputs): terminated exactly where it
    # took fewer samples than the same ray that never stops, and only where it became opaque
    opaque = TransferFunction1D(
        [[-2, 1, 1, 1], [4, 1, 1, 1]], [[-2, 0.0], [1.0, 0.0], [1.5, 1.0], [4, 1.0]], 0.5
    )
    w, h = 24, 20
    pixels = np.arange(w * h, dtype=np.int64)
    counts, inputs = {}, []
    real = module.march

    def spy(*args):
        inputs.append(args[:5])
        return real(*args)

    monkeypatch.setattr(module, "march", spy)
    for term in (0.9, 1.0):
        inputs.clear()
        _, renderer = draw(volume, opaque, camera, (w, h), step=0.5, options={"termination_alpha": term})
        rgba = np.empty((w * h, 4), np.float32)
        counts[term] = np.zeros((w * h, 4), np.int64)
        module.march_pixels(*inputs[0], pixels, rgba, counts[term])
        if term == 0.9:
            alpha = rgba[:, 3]
            assert renderer.last_frame.counters["rays_terminated"] == counts[term][:, 3].sum()
    stopped = counts[0.9][:, 3] == 1
    assert stopped.sum() > 0.2 * w * h
    np.testing.assert_array_equal(stopped, counts[0.9][:, 0] < counts[1.0][:, 0])
    assert np.all(alpha[stopped] >= 0.9)
    assert np.all(counts[1.0][:, 3] == 0)
