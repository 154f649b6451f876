"""Clipping in the renderers that declare `clip_region`: exact cuts against closed forms, the
choice of `auto`, and the work a moved plane does not redo. (The conformance kit's `clip_region`
check covers the composite closed form and the refusals on every registered renderer.)"""

from __future__ import annotations

import numpy as np
import pytest

import volren
from volren.model import Camera, RenderSettings, TransferFunction1D
from volren.model.clip_region import ClipPlane, ClipRegion
from volren.renderers.base import render_frame
from volren.renderers.registry import registry
from volren.testing import oracles
from volren.testing.render_helpers import ramp_maximum_on_cut
from volren.testing.scenes import lattice_volume

CLIPPING = [pytest.param(name, kind) for name, kind in
            (("raycast", "uniform"), ("reference", "uniform"), ("reference", "tet"), ("tetra", "tet"))]  # fmt: skip


@pytest.mark.parametrize(("name", "kind"), CLIPPING)
def test_a_maximum_projection_of_a_ramp_peaks_exactly_on_the_cut(name, kind):
    """s = x + 0.5 y is linear along every ray, so its maximum over the kept part of a ray lies at
    one of the kept interval's ends: the value there is the closed form, to float precision."""
    volume = lattice_volume(kind, lambda x, y, z: x + 0.5 * y, (9, 8, 7), (0.8, 1.0, 1.2), (-1.0, 0.5, 2.0))
    lo, hi = np.asarray(volume.bounds[0::2]), np.asarray(volume.bounds[1::2])
    centre = (lo + hi) / 2
    region = ClipRegion(
        (ClipPlane(tuple(centre), (-1.0, 0.3, 0.4)),), (lo[0], hi[0], lo[1], hi[1], lo[2], centre[2] + 1)
    )
    tf = TransferFunction1D([[-2, 0, 0, 0], [12, 1, 1, 1]], [[-2, 0.2], [12, 1.0]], 1.0)
    w = h = 36
    camera = Camera.orbit(volume.bounds, 35, 25, zoom=1.2)
    renderer = registry.create(name)
    renderer.set_volume(volume)
    renderer.set_transfer_function(tf)
    renderer.set_settings(RenderSettings(blend_mode="maximum", clip=region))
    image, _ = render_frame(renderer, camera, w, h)

    expected, compared = ramp_maximum_on_cut(camera, w, h, volume.bounds, region.half_spaces(), tf)
    assert np.abs(image - expected)[compared].max() < 1e-4


def test_auto_picks_a_renderer_that_clips():
    volume = lattice_volume("uniform", lambda x, y, z: x, (8, 8, 8))
    for kind in ("uniform", "tet"):
        volume = lattice_volume(kind, lambda x, y, z: x + y, (6, 6, 6))
        ready = volren.drawing(volume, size=32, clip_planes=[((2.0, 2.0, 2.0), (1.0, 0.0, 0.0))])
        assert registry.capabilities(ready.scene.renderer).kinds[kind].clip_region
        assert ready.scene.settings.clip.planes == (ClipPlane((2.0, 2.0, 2.0), (1.0, 0.0, 0.0)),)
        image = volren.render(volume, size=32, crop=(0, 2.5, 0, 5, 0, 5), azimuth=90)
        assert image[..., 3].max() > 0


def test_a_renderer_that_does_not_clip_refuses_in_one_line():
    volume = lattice_volume("tet", lambda x, y, z: x, (5, 5, 5))
    with pytest.raises(volren.VolrenError, match="renderer vtk does not clip tet volumes") as exc:
        volren.render(volume, renderer="vtk", size=16, clip_planes=[((1, 1, 1), (0, 0, 1))])
    assert "\n" not in str(exc.value)


def test_a_cap_with_nothing_cut_is_refused_in_one_line_as_on_the_command_line():
    volume = lattice_volume("uniform", lambda x, y, z: x, (5, 5, 5))
    with pytest.raises(volren.VolrenError, match="clip_cap: give clip_planes or crop") as exc:
        volren.render(volume, size=16, clip_cap=True)
    assert "\n" not in str(exc.value)


def test_moving_a_plane_keeps_raycasts_chosen_step_and_bricks():
    """A drag moves a plane every frame: the step search (hundreds of ms) and the brick
    classification serve the TF and the data and must not run again."""
    volume = lattice_volume("uniform", lambda x, y, z: np.sin(x) * np.cos(y) + z / 9, (24, 24, 24))
    renderer = registry.create("raycast")
    renderer.set_volume(volume)
    renderer.set_transfer_function(TransferFunction1D.ramp(-1.0, 3.0))
    camera = Camera.orbit(volume.bounds, 20, 10)
    for x in (4.0, 9.0, 15.0):
        clip = ClipRegion((ClipPlane((x, 0.0, 0.0), (1.0, 0.0, 0.0)),))
        renderer.set_settings(RenderSettings(step=1.0, clip=clip, options={"target_error": 0.01}))
        render_frame(renderer, camera, 32, 32)
        if x == 4.0:
            step, bricks = renderer._step, renderer._empty
        assert renderer._step is step and renderer._empty is bricks


@pytest.mark.gl
@pytest.mark.parametrize("path", ["march", "slices"])
@pytest.mark.parametrize("preintegration", [False, True])
def test_the_slicers_two_paths_cut_a_homogeneous_box_exactly(path, preintegration):
    """Both of the slicer's paths (a compute march and blended polygons) narrow each ray, or each
    fragment's segment, to the kept region in the shader: the cut lies on the plane, not on a
    slice, at every step."""
    volume = lattice_volume("uniform", 1.0, (6, 5, 7), (0.9, 1.1, 0.8), (0.5, -1.0, 2.0))
    lo, hi = np.asarray(volume.bounds[0::2]), np.asarray(volume.bounds[1::2])
    region = ClipRegion(
        (ClipPlane(tuple((lo + hi) / 2), (1.0, 0.7, -0.5)),), (lo[0], hi[0], lo[1], hi[1], 2.5, hi[2])
    )
    tf = TransferFunction1D.constant(0.4, (0.2, 0.9, 0.5), opacity_unit_distance=0.6)
    camera = Camera.orbit(volume.bounds, 25, 30, zoom=1.2)
    renderer = registry.create("slicer")
    renderer.set_volume(volume)
    renderer.set_transfer_function(tf)
    settings = RenderSettings(step=1.3, preintegration=preintegration, clip=region, options={"path": path})
    renderer.set_settings(settings)
    image, _ = render_frame(renderer, camera, 40, 40)
    lengths = oracles.box_path_lengths(camera, 40, 40, volume.bounds, region.half_spaces())
    expected = oracles.homogeneous_image(lengths, (0.2, 0.9, 0.5), 0.4, 0.6)
    assert np.sqrt(np.mean((image - expected) ** 2)) < 1e-4


@pytest.mark.gl
def test_tetras_gl_walk_cuts_a_homogeneous_mesh_exactly():
    """The compute-shader walk (a hardware GPU's default; here llvmpipe) cuts rays as the CPU walk
    does, in the mesh's coordinates moved to its centre."""
    volume = lattice_volume("tet", 1.0, (5, 6, 5), (0.9, 1.1, 0.8), (40.0, -1.0, 2.0))
    lo, hi = np.asarray(volume.bounds[0::2]), np.asarray(volume.bounds[1::2])
    region = ClipRegion(
        (ClipPlane(tuple((lo + hi) / 2), (1.0, -0.7, 0.5)),), (lo[0], hi[0], lo[1], 3.0, lo[2], hi[2])
    )
    tf = TransferFunction1D.constant(0.4, (0.2, 0.9, 0.5), opacity_unit_distance=0.6)
    camera = Camera.orbit(volume.bounds, 25, 30, zoom=1.2)
    renderer = registry.create("tetra")
    renderer.set_volume(volume)
    renderer.set_transfer_function(tf)
    renderer.set_settings(RenderSettings(clip=region, options={"backend": "gl"}))
    image, _ = render_frame(renderer, camera, 40, 40)
    lengths = oracles.box_path_lengths(camera, 40, 40, volume.bounds, region.half_spaces())
    expected = oracles.homogeneous_image(lengths, (0.2, 0.9, 0.5), 0.4, 0.6)
    assert np.sqrt(np.mean((image - expected) ** 2)) < 1e-4


def test_cached_reference_images_are_keyed_on_the_clip_region(tmp_path):
    """The cache kept the reference's settings without the clip region: a clipped scene's reference
    came back uncut (from the cache or drawn uncut)."""
    from volren.testing.reference_images import reference_image

    volume = lattice_volume("uniform", lambda x, y, z: x + y, (5, 5, 5))
    tf = TransferFunction1D.ramp(0.0, 8.0)
    camera = Camera.orbit(volume.bounds, 20, 10)
    cut = RenderSettings(clip=ClipRegion((ClipPlane((2.0, 2.0, 2.0), (1.0, 0.0, 0.0)),)))
    whole = reference_image(volume, tf, camera, 16, 16, folder=tmp_path)
    clipped = reference_image(volume, tf, camera, 16, 16, cut, folder=tmp_path)
    assert len(list(tmp_path.glob("*.npy"))) == 2
    assert clipped[..., 3].sum() < 0.8 * whole[..., 3].sum()


@pytest.mark.parametrize(("name", "kind"), [("reference", "uniform"), ("reference", "tet"), ("tetra", "tet")])
def test_a_shaded_cut_face_is_lit_by_the_planes_normal(name, kind):
    """Parallel view, headlight: the half vector is the light, so a face of normal n shows
    c (ambient + diffuse |n.L|) + specular |n.L|^power (two-sided Blinn-Phong, DESIGN's shading)."""
    volume = lattice_volume(kind, lambda x, y, z: x + 0.5 * y, (6, 5, 5))
    tf = TransferFunction1D([[0.0, 0.2, 0.8, 0.4], [8.0, 0.9, 0.3, 0.6]], [[0.0, 0.5], [8.0, 0.5]], 1.0)
    camera = Camera.orbit(volume.bounds, 20, 15, parallel=True)
    normal = np.array([-0.8, -0.3, -0.5])
    region = ClipRegion((ClipPlane((2.5, 2.0, 2.0), tuple(normal)),), cap=True)
    settings = RenderSettings(shade=True, clip=region)
    renderer = registry.create(name)
    renderer.set_volume(volume)
    renderer.set_transfer_function(tf)
    renderer.set_settings(settings)
    image, _ = render_frame(renderer, camera, 32, 32)
    through, entry = oracles.entered_through_a_plane(camera, 32, 32, volume.bounds, region.half_spaces())
    rgb, _ = tf.sample(entry[..., 0] + 0.5 * entry[..., 1])
    ndl = abs(float(normal @ camera.direction)) / np.linalg.norm(normal)
    lit = np.clip(
        rgb * (settings.ambient + settings.diffuse * ndl) + settings.specular * ndl**settings.specular_power,
        0,
        1,
    )
    faces = through & ~oracles.at_an_edge(through)
    faces[[0, -1], :] = faces[:, [0, -1]] = False  # the image's border: its neighbours are not all known
    assert faces.sum() > 50
    assert np.abs(image[faces][:, :3] - lit[faces]).max() < 1e-5 and np.all(image[faces][:, 3] == 1.0)
