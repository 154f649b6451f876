"""The object-order plugin under a clip region (`RenderSettings.clip`: oblique planes and a crop box):
each pixel's ray is narrowed to the kept region in the ray table, so the cut is flat and exact
(closed forms to float precision), skipping still changes no pixel, and moving a plane redoes none
of what serves the TF and the volume."""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest
from volren_objectorder import ObjectOrderRenderer

from volren.kernels.sample_placement import pixel_phases
from volren.model import Camera, RenderSettings, TransferFunction1D, UniformVolume
from volren.model.clip_region import ClipPlane, ClipRegion
from volren.testing import image_error, oracles
from volren.testing.render_helpers import SHELL_TF, field, ramp_maximum_on_cut, render_checked
from volren.testing.scenes import lattice_volume

draw = partial(render_checked, ObjectOrderRenderer)


def _oblique_region(bounds: tuple[float, ...]) -> ClipRegion:
    """An oblique plane through the box's centre and a crop box that takes a slab off its top."""
    lo, hi = np.asarray(bounds[0::2]), np.asarray(bounds[1::2])
    centre = (lo + hi) / 2
    return ClipRegion(
        (ClipPlane(tuple(centre), (-1.0, 0.3, 0.4)),), (lo[0], hi[0], lo[1], hi[1], lo[2], centre[2] + 1.0)
    )


@pytest.mark.parametrize("parallel", [True, False])
def test_the_ray_table_holds_the_kept_interval(parallel):
    """Each ray's entry t0 and the end of its last segment are the kept interval's ends (float64
    brute force), and its segments stay on the unclipped ray's planes: the same count of whole
    steps between them."""
    from volren_objectorder.patterns import ray_end, ray_table

    volume = field((10, 11, 12), spacing=(1.0, 0.8, 1.3))
    camera = Camera.orbit(volume.bounds, 35, 25, zoom=1.2, parallel=parallel)
    width, height, h = 24, 20, 0.5
    region = _oblique_region(volume.bounds)
    planes = region.half_spaces_in_grid(np.asarray(volume.origin), np.asarray(volume.spacing))
    phases = pixel_phases("interleaved", width, height, 0)
    rays = ray_table(camera, volume, width, height, h, phases, planes=planes)
    origins, directions = camera.pixel_rays(width, height)
    near, far = camera.clipping_range
    t_far = (far - near) / (directions @ camera.direction)
    t0, t1 = (
        t.reshape(-1)
        for t in oracles.kept_interval(origins, directions, t_far, volume.bounds, region.half_spaces())[:2]
    )
    hit = rays.count > 0
    assert hit.sum() > 0.1 * width * height and (t1 > t0 + 1e-6).sum() == hit.sum()
    np.testing.assert_allclose(rays.t0[hit], t0[hit], atol=1e-9)
    ends = np.array(
        [ray_end(rays.t0[p], rays.first[p], h, rays.count[p], rays.last[p]) for p in np.flatnonzero(hit)]
    )
    np.testing.assert_allclose(ends, t1[hit], atol=1e-9)
    # the first segment ends on a plane t = (phase + j) h counted from the ray's origin
    boundary = (rays.t0[hit] + rays.first[hit]) / h - phases[hit]
    inner = rays.count[hit] > 1
    np.testing.assert_allclose(boundary[inner], np.round(boundary[inner]), atol=1e-9)


@pytest.mark.parametrize("parallel", [True, False])
@pytest.mark.parametrize("settings", [{}, {"preintegration": True}, {"step": 0.25, "shade": True},
                                      {"step": 1.0, "preintegration": True},
                                      {"options": {"hidden_volume_removal": False, "classification_table": 0}}])  # fmt: skip
def test_a_clip_region_cuts_a_constant_box_exactly(parallel, settings):
    """A constant box cut by an oblique plane and a crop box: the closed form 1 - (1 - a)^(L / d_u)
    with L each ray's length in the kept region, to float precision (the first and last segments
    end on the cut, their opacity corrected to their length)."""
    volume = UniformVolume(
        np.full((6, 7, 8), 1.0, np.float32), spacing=(0.9, 1.1, 1.0), origin=(0.5, -1.0, 2.0)
    )
    tf = TransferFunction1D.constant(0.15, (0.4, 0.7, 0.2), opacity_unit_distance=0.7)
    camera = Camera.orbit(volume.bounds, 35, -20, zoom=1.3, parallel=parallel)
    region = _oblique_region(volume.bounds)
    image, _ = draw(volume, tf, camera, (40, 40), clip=region, **settings)
    expected = oracles.homogeneous_image(
        oracles.box_path_lengths(camera, 40, 40, volume.bounds, region.half_spaces()),
        (0.4, 0.7, 0.2),
        0.15,
        0.7,
    )
    whole = oracles.homogeneous_image(
        oracles.box_path_lengths(camera, 40, 40, volume.bounds), (0.4, 0.7, 0.2), 0.15, 0.7
    )
    assert image_error(expected, whole).rmse > 0.03  # the cut shows
    assert image_error(image, expected).rmse < 1e-5


@pytest.mark.parametrize("parallel", [True, False])
def test_a_maximum_projection_of_a_ramp_peaks_exactly_on_the_cut(parallel):
    """s = x + 0.5 y is linear along every ray, so its maximum over the kept part of a ray lies at
    one of the kept interval's ends: the value there is the closed form, to float precision."""
    volume = lattice_volume(
        "uniform", lambda x, y, z: x + 0.5 * y, (9, 8, 7), (0.8, 1.0, 1.2), (-1.0, 0.5, 2.0)
    )
    region = _oblique_region(volume.bounds)
    tf = TransferFunction1D([[-2, 0, 0, 0], [12, 1, 1, 1]], [[-2, 0.2], [12, 1.0]], 1.0)
    w = h = 36
    camera = Camera.orbit(volume.bounds, 35, 25, zoom=1.2, parallel=parallel)
    image, _ = draw(volume, tf, camera, (w, h), blend_mode="maximum", clip=region)

    expected, compared = ramp_maximum_on_cut(camera, w, h, volume.bounds, region.half_spaces(), tf)
    assert np.abs(image - expected)[compared].max() < 1e-4


@pytest.mark.parametrize("parallel", [False, True])
def test_octree_skipping_changes_no_pixel_of_a_clipped_frame(parallel):
    """Pre-integrated, a clipped ray's last piece runs from its last sample on to the cut, inside
    the volume: a step in x seen along +x, cut at x = 5.3, the pieces from last samples in the
    cells left of x = 5 (transparent, also dilated toward the eye) to values above the TF's spike
    on the cut. The octree then dilates both ways (as for a far plane through the volume), and
    skipping draws what skipping nothing draws (one-sided: up to 0.24 off on 14-45 pixels)."""
    values = np.broadcast_to((np.arange(12) >= 6).astype(np.float32), (8, 8, 12)).copy()
    volume = UniformVolume(values)
    spike = TransferFunction1D(
        [[0, 1, 0.5, 0.2], [1, 0.3, 0.6, 1.0]], [[0.0, 0.0], [0.05, 0.0], [0.5, 1.0]], 0.5
    )
    region = ClipRegion((ClipPlane((5.3, 0.0, 0.0), (-1.0, 0.0, 0.0)),))
    options = {"hidden_volume_removal": False, "depth_offsets": "random"}
    for az, el in ((-90, 0), (-80, 5), (-100, -5)):
        camera = Camera.orbit(volume.bounds, az, el, parallel=parallel)
        common = {"preintegration": True, "step": 0.95, "clip": region}
        on, _ = draw(volume, spike, camera, (36, 30), **common, options=options)
        off, _ = draw(
            volume, spike, camera, (36, 30), **common, options={**options, "octree_skipping": False}
        )
        assert on[..., 3].max() > 0.2
        np.testing.assert_allclose(on, off, atol=1e-6, err_msg=str(camera))


def test_moving_a_plane_keeps_the_octree_its_classification_and_the_phases():
    """A drag moves a plane every frame: the min-max octree (per volume), its classification (per
    TF) and the pixels' phases serve the TF and the data and are neither rebuilt nor redone."""
    volume = field((20, 18, 16))
    renderer = ObjectOrderRenderer()
    renderer.set_volume(volume)
    renderer.set_transfer_function(SHELL_TF)
    camera = Camera.orbit(volume.bounds, 20, 10)
    images = []
    for x in (4.0, 9.0, 15.0):
        clip = ClipRegion((ClipPlane((x, 0.0, 0.0), (1.0, 0.0, 0.0)),))
        renderer.set_settings(RenderSettings(preintegration=True, clip=clip))
        images.append(renderer.render(camera, 32, 32))
        if x == 4.0:
            octree, phases = renderer.octree, renderer._phases
            (classification,) = octree._cache.values()
        assert renderer.octree is octree and renderer._phases is phases
        assert list(octree._cache.values()) == [classification]
    assert image_error(images[0], images[-1]).rmse > 0.01  # the plane moved what is drawn
