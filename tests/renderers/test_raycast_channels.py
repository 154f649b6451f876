"""raycast on multi-channel volumes (`march_channels`, and the C march's channel path): the model of
`volren.model.channels` against closed forms, the plain march and its float64 oracle."""

from __future__ import annotations

import math

import numpy as np
import pytest

from volren.errors import VolrenError
from volren.model import BlendMode, Camera, RenderSettings, TransferFunction1D, UniformVolume
from volren.model.channels import ChannelSet, ChannelTransferFunction
from volren.renderers.raycast import march_native
from volren.renderers.raycast.renderer import RaycastRenderer

SIZE = 40
GREEN = TransferFunction1D([[0.0, 0.0, 1.0, 0.0], [1.0, 0.2, 1.0, 0.2]], [[0.0, 0.0], [1.0, 0.4]])
MAGENTA = TransferFunction1D([[0.0, 1.0, 0.0, 1.0]], [[0.2, 0.0], [0.8, 0.6], [1.0, 0.1]])


def _fields(n: int = 24) -> np.ndarray:
    z, y, x = np.mgrid[0:n, 0:n, 0:n].astype(float)
    a = np.exp(-(((x - n / 3) ** 2 + (y - n / 2) ** 2 + (z - n / 2) ** 2) / (n / 4) ** 2))
    b = np.exp(-(((x - 2 * n / 3) ** 2 + (y - n / 2) ** 2 + (z - n / 2) ** 2) / (n / 4) ** 2))
    return np.stack([a, b]).astype(np.float32)


def _volume(fields: np.ndarray) -> UniformVolume:
    return UniformVolume(fields[0], channels=ChannelSet(fields))


def _renderer(volume: UniformVolume, tf, **options) -> RaycastRenderer:
    renderer = RaycastRenderer()
    renderer.set_volume(volume)
    renderer.set_settings(RenderSettings(step=0.5, preintegration=False, options=options))
    renderer.set_transfer_function(tf)
    return renderer


def _camera(volume: UniformVolume) -> Camera:
    return Camera.orbit(volume.bounds, 30.0, 20.0)


@pytest.mark.parametrize("numba", [True, False])
def test_one_channel_draws_the_plain_march(numba: bool) -> None:
    """A channel's table holds depth (w tau h) where the plain march's holds opacity: the two
    interpolate differently between entries, by far less than an 8-bit step."""
    fields = _fields()
    volume = UniformVolume(fields[0], channels=ChannelSet(fields[:1]))
    plain = _renderer(volume, GREEN)
    mixed = _renderer(volume, ChannelTransferFunction([GREEN]))
    camera = _camera(volume)
    if numba:
        with march_native.numba_only():
            want, got = plain.render(camera, SIZE, SIZE), mixed.render(camera, SIZE, SIZE)
    else:
        want, got = plain.render(camera, SIZE, SIZE), mixed.render(camera, SIZE, SIZE)
    assert want[..., 3].max() > 0.2
    np.testing.assert_allclose(got, want, atol=2e-4)


def test_constant_channels_absorb_as_their_summed_extinction() -> None:
    """Two constant channels through a slab seen along x: alpha = 1 - exp(-(w0 tau0 + w1 tau1) L),
    colour the extinction-weighted mean of the two colours, whatever the step."""
    nx = 9
    fields = np.stack([np.full((5, 5, nx), 0.5), np.full((5, 5, nx), 0.7)]).astype(np.float32)
    volume = _volume(fields)
    tf = ChannelTransferFunction([GREEN, MAGENTA], weights=[1.0, 2.0])
    camera = Camera.orbit(volume.bounds, 90.0, 0.0, parallel=True)
    tau0 = -math.log1p(-0.2)  # GREEN at 0.5
    tau1 = 2.0 * -math.log1p(-0.5)  # MAGENTA at 0.7, weight 2
    alpha = 1 - math.exp(-(tau0 + tau1) * (nx - 1))
    rgb0, _ = GREEN.sample([0.5])
    colour = (tau0 * rgb0[0] + tau1 * np.array([1.0, 0.0, 1.0])) / (tau0 + tau1) * alpha
    for numba in (True, False):
        renderer = _renderer(volume, tf, termination_alpha=1.0)
        if numba:
            with march_native.numba_only():
                image = renderer.render(camera, 8, 8)
        else:
            image = renderer.render(camera, 8, 8)
        np.testing.assert_allclose(image[4, 4], [*colour, alpha], atol=2e-5)


def test_a_hidden_channel_adds_nothing_and_weights_scale_density() -> None:
    fields = _fields()
    volume = _volume(fields)
    camera = _camera(volume)
    alone = _renderer(
        UniformVolume(fields[0], channels=ChannelSet(fields[:1])), ChannelTransferFunction([GREEN])
    )
    hidden = _renderer(volume, ChannelTransferFunction([GREEN, MAGENTA], visible=[True, False]))
    np.testing.assert_allclose(hidden.render(camera, SIZE, SIZE), alone.render(camera, SIZE, SIZE), atol=1e-6)
    # weight 2 doubles the extinction, as half the opacity unit distance does (tau = -ln(1 - a) / d_u)
    doubled = TransferFunction1D(GREEN.color_points, GREEN.opacity_points, opacity_unit_distance=0.5)
    twice = _renderer(volume, ChannelTransferFunction([GREEN, MAGENTA], weights=[2.0, 0.0]))
    dense = _renderer(volume, ChannelTransferFunction([doubled, MAGENTA], weights=[1.0, 0.0]))
    image = twice.render(camera, SIZE, SIZE)
    assert image[..., 3].max() > 0.3
    np.testing.assert_allclose(image, dense.render(camera, SIZE, SIZE), atol=1e-6)


@pytest.mark.skipif(not march_native.vector_path(), reason="the C march does not build here")
@pytest.mark.parametrize("dtype", [np.float32, np.uint8])
def test_the_c_march_mixes_channels_as_numba_does(dtype: type) -> None:
    fields = _fields()
    if dtype == np.uint8:
        fields = (fields * 255).astype(np.uint8)
    volume = _volume(fields)
    top = float(fields.max())
    tfs = [
        TransferFunction1D(t.color_points * [top, 1, 1, 1], t.opacity_points * [top, 1])
        for t in (GREEN, MAGENTA)
    ]
    renderer = _renderer(volume, ChannelTransferFunction(tfs), termination_alpha=0.95)
    camera = _camera(volume)
    c_image = renderer.render(camera, SIZE, SIZE)
    c_samples = renderer.last_frame.counters["samples"]
    with march_native.numba_only():
        numba_image = renderer.render(camera, SIZE, SIZE)
    assert c_image[..., 3].max() > 0.3
    np.testing.assert_allclose(c_image, numba_image, atol=5e-5)  # the vector path's single precision
    assert abs(c_samples - renderer.last_frame.counters["samples"]) <= 0.001 * c_samples


def test_nan_in_one_channel_leaves_the_others() -> None:
    fields = _fields()
    fields[1, :, :, : fields.shape[3] // 2] = np.nan
    volume = _volume(fields)
    camera = Camera.orbit(volume.bounds, 0.0, 0.0, parallel=True)
    both = _renderer(volume, ChannelTransferFunction([GREEN, MAGENTA])).render(camera, SIZE, SIZE)
    green = _renderer(volume, ChannelTransferFunction([GREEN, MAGENTA], visible=[True, False])).render(
        camera, SIZE, SIZE
    )
    assert np.isfinite(both).all()
    left = slice(0, SIZE // 2 - 2)  # where the second channel is NaN all along the ray
    np.testing.assert_allclose(both[:, left], green[:, left], atol=1e-6)
    assert np.abs(both[:, SIZE // 2 + 2 :] - green[:, SIZE // 2 + 2 :]).max() > 0.05


def test_skipping_changes_no_pixel() -> None:
    fields = _fields(32)
    volume = _volume(fields)
    late = TransferFunction1D(GREEN.color_points, [[0.1, 0.0], [1.0, 0.4]])  # clear in the faint corners
    tf = ChannelTransferFunction([late, MAGENTA])
    camera = _camera(volume)
    skipped = _renderer(volume, tf)
    full = _renderer(volume, tf, empty_space_skipping=False)
    assert np.array_equal(skipped.render(camera, SIZE, SIZE), full.render(camera, SIZE, SIZE))
    assert skipped.last_frame.counters["samples"] < full.last_frame.counters["samples"]


def test_refusals() -> None:
    fields = _fields(8)
    tf = ChannelTransferFunction([GREEN, MAGENTA])
    bare = _renderer(UniformVolume(fields[0]), tf)
    with pytest.raises(VolrenError, match="has no channels"):
        bare.render(_camera(bare.volume), 8, 8)
    three = _renderer(UniformVolume(fields[0], channels=ChannelSet(np.stack([*fields, fields[0]]))), tf)
    with pytest.raises(VolrenError, match="has 3 channels"):
        three.render(_camera(three.volume), 8, 8)
    volume = _volume(fields)
    renderer = _renderer(volume, tf)
    renderer.set_settings(RenderSettings(preintegration=True))
    with pytest.raises(VolrenError, match="pre-integration of several channels"):
        renderer.render(_camera(volume), 8, 8)
    renderer.set_settings(RenderSettings(preintegration=False, blend_mode=BlendMode.MAXIMUM))
    with pytest.raises(VolrenError, match="composite only"):
        renderer.render(_camera(volume), 8, 8)
