"""`vtk` on multi-channel volumes (a vtkMultiVolume: `volren.renderers.vtk_mappers.channels`) against
the summed-extinction model of `volren.model.channels`: closed forms, the plain volume, `reference`.

Why these bounds (measured with VTK 9.7.2 on Mesa llvmpipe, 8-bit framebuffer, step 0.5): the
multi-volume multiplies each step's per-channel transmittances, so the summed extinction's alpha is
exact up to rounding (slab alpha 0.969 for 0.968); the colours of one step mix in input order, an
O(h) error in the colour (slab RGB off by up to 0.027, RMSE 0.020); the three-channel scene is
0.022 from `reference` at step 0.5 and 0.011 at 0.25.
"""

from __future__ import annotations

import numpy as np
import pytest

from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.channels import ChannelSet, ChannelTransferFunction
from volren.model.clip_region import ClipPlane, ClipRegion
from volren.model.settings import BlendMode, RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import UniformVolume
from volren.renderers.vtk_mappers.channels import MAX_VTK_CHANNELS
from volren.renderers.vtk_mappers.renderer import VtkRenderer
from volren.testing.channel_scenes import channel_scene, channel_slab, channel_slab_rgba
from volren.testing.reference_images import reference_image
from volren.testing.scenes import axis_camera

pytestmark = [pytest.mark.vtk, pytest.mark.usefixtures("opengl")]

LSB = 1.0 / 255.0
SIZE = 32


def rmse(a, b) -> float:
    return float(np.sqrt(np.mean((np.asarray(a, np.float64) - np.asarray(b, np.float64)) ** 2)))


def draw(volume, tf, camera, size=SIZE, **settings) -> np.ndarray:
    with VtkRenderer() as renderer:
        renderer.set_volume(volume)
        renderer.set_settings(RenderSettings(**settings))
        renderer.set_transfer_function(tf)
        return renderer.render(camera, size, size)


def fields_of(volume: UniformVolume) -> np.ndarray:
    assert volume.channels is not None
    return volume.channels.values


def slab_view(volume: UniformVolume, sign: float) -> Camera:
    b = volume.bounds
    return axis_camera(b, 0, sign, 0.35 * min(b[3] - b[2], b[5] - b[4]))


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_constant_two_channels_have_the_summed_extinction(sign: float) -> None:
    """Two constant media in one box: alpha is 1 - exp(-(w0 tau0 + w1 tau1) L) to the 8-bit step;
    the colour is the extinction-weighted mix up to the per-step mixing order (module docstring)."""
    volume, tf = channel_slab()
    image = draw(volume, tf, slab_view(volume, sign), 16)
    want = channel_slab_rgba()
    assert np.abs(image[..., 3] - want[3]).max() <= 2 * LSB
    assert np.abs(image[..., :3] - want[:3]).max() <= 0.035


def test_one_channel_draws_the_plain_volume() -> None:
    """A single channel at weight 1 is the plain volume with that TF (the same VTK ray caster;
    measured identical)."""
    volume, tf = channel_scene()
    fields = fields_of(volume)
    one = UniformVolume(fields[1], spacing=volume.spacing, channels=ChannelSet(fields[1:2]))
    camera = Camera.orbit(volume.bounds, 30, 25, zoom=1.2)
    mixed = draw(one, ChannelTransferFunction([tf.tfs[1]]), camera)
    plain = draw(UniformVolume(fields[1], spacing=volume.spacing), tf.tfs[1], camera)
    assert mixed[..., 3].max() > 0.5
    assert np.abs(mixed - plain).max() <= LSB


def test_a_weight_scales_the_extinction() -> None:
    """Weight w on one channel equals the plain volume whose TF has opacity 1 - (1 - a)^w: for a
    constant opacity that is the same TF over a unit distance d / w, exactly (measured identical;
    the weight ignored: 0.33 off)."""
    volume, tf = channel_scene()
    fields = fields_of(volume)
    base = TransferFunction1D([[-3, 0.0, 1.0, 1.0], [10, 0.0, 0.6, 1.0]], [[-3, 0.15]], 1.0)
    one = UniformVolume(fields[2], spacing=volume.spacing, channels=ChannelSet(fields[2:3]))
    camera = Camera.orbit(volume.bounds, 30, 25, zoom=1.2)
    weighted = draw(one, ChannelTransferFunction([base], [2.5]), camera)
    scaled = TransferFunction1D(base.color_points, base.opacity_points, 1.0 / 2.5)
    plain = draw(UniformVolume(fields[2], spacing=volume.spacing), scaled, camera)
    assert weighted[..., 3].max() > 0.5
    assert np.abs(weighted - plain).max() <= LSB


@pytest.mark.parametrize(("step", "bound"), [(0.5, 0.03), (0.25, 0.016)])
def test_three_channels_against_reference(step: float, bound: float) -> None:
    """The kit's three overlapping channels (one at weight 2): within the measured error, which
    halves with the step (the colour mixing order is an O(h) error)."""
    volume, tf = channel_scene()
    camera = Camera.orbit(volume.bounds, 30, 25, zoom=1.2)
    reference = reference_image(volume, tf, camera, SIZE, SIZE)
    assert rmse(draw(volume, tf, camera, step=step), reference) <= bound


def test_hidden_channels_add_nothing() -> None:
    """Hiding a channel is drawing the others alone; hiding all draws nothing."""
    volume, tf = channel_scene()
    camera = Camera.orbit(volume.bounds, 30, 25, zoom=1.2)
    hidden = tf.copy()
    hidden.set_visible(1, False)
    fields = fields_of(volume)[[0, 2]]
    two = UniformVolume(fields[0], spacing=volume.spacing, channels=ChannelSet(fields))
    others = ChannelTransferFunction([tf.tfs[0], tf.tfs[2]], [tf.weights[0], tf.weights[2]])
    assert np.abs(draw(volume, hidden, camera) - draw(two, others, camera)).max() <= 2 * LSB
    for c in range(3):
        hidden.set_visible(c, False)
    assert not draw(volume, hidden, camera).any()


def test_clipped_channels_against_reference() -> None:
    """The GPU mapper's clipping planes cut the multi-volume too (measured RMSE 0.028)."""
    volume, tf = channel_scene()
    camera = Camera.orbit(volume.bounds, 30, 25, zoom=1.2)
    clip = ClipRegion(planes=(ClipPlane((5.0, 5.0, 5.0), (1.0, 0.3, 0.2)),))
    reference = reference_image(volume, tf, camera, SIZE, SIZE, RenderSettings(clip=clip))
    whole = reference_image(volume, tf, camera, SIZE, SIZE)
    image = draw(volume, tf, camera, clip=clip)
    assert rmse(image, reference) <= 0.04
    assert rmse(image, whole) > 0.15


def many_channels(count: int) -> tuple[UniformVolume, ChannelTransferFunction]:
    volume, tf = channel_scene()
    fields = fields_of(volume)[[c % 3 for c in range(count)]]
    many = UniformVolume(fields[0], spacing=volume.spacing, channels=ChannelSet(fields))
    return many, ChannelTransferFunction([tf.tfs[c % 3] for c in range(count)], [0.3] * count)


def test_more_channels_than_the_mapper_has_inputs_are_refused_in_one_line() -> None:
    volume, tf = many_channels(MAX_VTK_CHANNELS + 1)
    camera = Camera.orbit(volume.bounds, 30, 25, zoom=1.2)
    with pytest.raises(VolrenError, match=f"at most {MAX_VTK_CHANNELS} channels") as info:
        draw(volume, tf, camera, 8)
    assert "\n" not in str(info.value)
    tf.set_visible(0, False)  # the limit is on the channels drawn
    assert draw(volume, tf, camera, 8)[..., 3].max() > 0.1


@pytest.mark.parametrize(
    ("settings", "words"),
    [
        ({"options": {"mapper": "fixed_point"}}, "GPU ray cast mapper"),
        ({"options": {"mapper": "smart"}}, "GPU ray cast mapper"),
        ({"blend_mode": BlendMode.MAXIMUM}, "composite only"),
        ({"shade": True}, "unshaded only"),
    ],
)
def test_what_vtk_cannot_mix_is_refused_in_one_line(settings: dict, words: str) -> None:
    volume, tf = channel_scene()
    camera = Camera.orbit(volume.bounds, 30, 25, zoom=1.2)
    calls: list[float] = []
    with VtkRenderer() as renderer:
        renderer.set_volume(volume)
        renderer.set_settings(RenderSettings(**settings))
        renderer.set_transfer_function(tf)
        with pytest.raises(VolrenError, match=words) as info:
            renderer.render(camera, 8, 8, calls.append)
    assert "\n" not in str(info.value) and not calls


def test_the_plain_volume_draws_again_after_channels() -> None:
    """One renderer switching from channels back to the volume's own TF draws what a fresh one does."""
    volume, tf = channel_scene()
    camera = Camera.orbit(volume.bounds, 30, 25, zoom=1.2)
    with VtkRenderer() as renderer:
        renderer.set_volume(volume)
        renderer.set_transfer_function(tf)
        renderer.render(camera, SIZE, SIZE)
        renderer.set_transfer_function(tf.tfs[0])
        again = renderer.render(camera, SIZE, SIZE)
    assert np.array_equal(again, draw(volume, tf.tfs[0], camera))


def test_a_channel_with_nan_adds_nothing_there() -> None:
    """Channel 0 is NaN over half the grid: the others still draw there (each channel's non-finite
    points get a transparent stand-in below its data, as the plain volume's do; measured RMSE 0.021)."""
    volume, tf = channel_scene()
    fields = fields_of(volume).copy()
    fields[0, :, :, 6:] = np.nan
    holed = UniformVolume(fields[0], spacing=volume.spacing, channels=ChannelSet(fields))
    camera = Camera.orbit(volume.bounds, 30, 25, zoom=1.2)
    reference = reference_image(holed, tf, camera, SIZE, SIZE)
    assert rmse(draw(holed, tf, camera), reference) <= 0.03
