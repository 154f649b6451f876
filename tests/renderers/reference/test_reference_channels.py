"""The reference renderer with multi-channel volumes (`volren.model.channels`) against exact oracles.

The oracles never call the renderer's integration code: the plain reference (one channel is the
plain model), closed forms of constant media whose extinctions add, and a float64 brute-force
integral of the channel model along each ray from `ChannelTransferFunction.extinction_emission`.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from volren.errors import VolrenError, VolrenWarning
from volren.model import BlendMode, Camera, RenderSettings, TetVolume, TransferFunction1D, UniformVolume
from volren.model.channels import ChannelSet, ChannelTransferFunction
from volren.model.clip_region import ClipPlane, ClipRegion
from volren.model.transfer_function_2d import TFWidget, TransferFunction2D
from volren.renderers.reference import ReferenceRenderer
from volren.testing.channel_scenes import (
    SLAB_COLOURS,
    SLAB_DIMS,
    SLAB_SPACING,
    channel_slab,
    channel_slab_rgba,
    slab_extinctions,
)
from volren.testing.oracles import pixel_kept_intervals
from volren.testing.scenes import axis_camera


def render(volume, tf, camera, n, **settings):
    """The reference's float64 image of `volume` with `tf` (n x n) and the renderer."""
    renderer = ReferenceRenderer()
    renderer.set_volume(volume)
    renderer.set_transfer_function(tf)
    renderer.set_settings(RenderSettings(**settings))
    image = renderer.render(camera, n, n)
    assert image.dtype == np.float32 and np.all(image[..., :3] <= image[..., 3:4] + 1e-6)
    assert renderer.last_frame.counters["unconverged_rays"] == 0
    return renderer.last_rgba64, renderer


def smooth_values(shape, phase=0.0):
    z, y, x = np.mgrid[0 : shape[0], 0 : shape[1], 0 : shape[2]].astype(np.float64)
    return np.sin(x / 3.0 + phase) + np.cos(y / 4.0) + z / 8.0


def with_channels(*fields, spacing=(1.0, 0.9, 1.1)):
    """A volume whose channels are `fields` (its own values the first one's, NaN made 0)."""
    values = np.stack(fields)
    return UniformVolume(np.nan_to_num(values[0]), spacing=spacing, channels=ChannelSet(values))


BASE = TransferFunction1D([[-2, 0.2, 0.3, 1.0], [1.0, 0.9, 0.1, 0.4], [4, 1.0, 0.8, 0.1]],
                          [[-1, 0.0], [1.2, 0.5], [4, 0.7]], 1.5)  # fmt: skip
OTHER = TransferFunction1D([[-1, 1.0, 0.0, 1.0], [3, 0.2, 1.0, 0.2]], [[-1, 0.6], [0.5, 0.1], [3, 0.4]], 0.8)
THIRD = TransferFunction1D([[-2, 0.0, 1.0, 1.0], [4, 1.0, 1.0, 0.0]], [[0, 0.0], [4, 0.9]], 2.0)


# ------------------------------------------------------------------------- the plain model
@pytest.mark.parametrize("clip", [False, True], ids=["whole", "clip plane"])
def test_one_channel_is_the_plain_reference(clip):
    shape = (12, 13, 14)
    values = smooth_values(shape)
    values[5, 6, 3] = np.nan  # its eight cells are transparent in both
    plain = UniformVolume(values, spacing=(1.0, 0.9, 1.1))
    one = UniformVolume(np.zeros(shape), spacing=(1.0, 0.9, 1.1), channels=ChannelSet(values[None]))
    camera = Camera.orbit(plain.bounds, 30, 20)
    region = ClipRegion((ClipPlane((7.0, 6.0, 6.0), (1.0, 0.4, -0.3)),)) if clip else ClipRegion()
    expected, _ = render(plain, BASE, camera, 32, clip=region, options={"tolerance": 1e-6})
    image, renderer = render(one, ChannelTransferFunction([BASE]), camera, 32, clip=region,
                             options={"tolerance": 1e-6})  # fmt: skip
    assert expected[..., 3].max() > 0.5 and (expected[..., 3] == 0).sum() > 50
    assert np.abs(image - expected).max() < 1e-5
    assert renderer.last_frame.counters["channels_drawn"] == 1


# --------------------------------------------------------------------- constant media add up
@pytest.mark.parametrize("sign", [1.0, -1.0], ids=["from +x", "from -x"])
def test_a_constant_two_channel_slab_is_the_closed_form_of_the_summed_extinction(sign):
    volume, tf = channel_slab()
    b = volume.bounds
    image, renderer = render(volume, tf, axis_camera(b, 0, sign, 0.3 * (b[3] - b[2])), 16,
                             options={"tolerance": 1e-8})  # fmt: skip
    # alpha = 1 - exp(-(w0 tau0 + w1 tau1) L), colour = (w0 tau0 c0 + w1 tau1 c1) / (w0 tau0 + w1 tau1) alpha
    (t0, t1), length = slab_extinctions(), SLAB_SPACING[0] * (SLAB_DIMS[0] - 1)
    alpha = 1.0 - math.exp(-(t0 + t1) * length)
    colour = (t0 * np.asarray(SLAB_COLOURS[0]) + t1 * np.asarray(SLAB_COLOURS[1])) / (t0 + t1) * alpha
    assert np.abs(image - np.array([*colour, alpha])).max() < 1e-7
    assert np.abs(channel_slab_rgba() - np.array([*colour, alpha])).max() < 1e-15
    assert renderer.last_frame.counters["channels_drawn"] == 2


def test_a_constant_slab_in_perspective_has_the_alpha_of_each_rays_length():
    volume, tf = channel_slab()
    n = 24
    camera = Camera.orbit(volume.bounds, 25, 35, zoom=1.3)
    image, _ = render(volume, tf, camera, n, options={"tolerance": 1e-8})
    _, _, t0, t1, _ = pixel_kept_intervals(camera, n, n, volume.bounds)
    lengths = np.maximum(t1 - t0, 0.0)
    expected = np.array([channel_slab_rgba(float(ell)) for ell in lengths.ravel()]).reshape(n, n, 4)
    assert (lengths > 0).sum() > 100 and (lengths == 0).sum() > 20
    assert np.abs(image - expected).max() < 1e-7


# ------------------------------------------------------------------ visibility and weights
def three_channels():
    shape = (7, 8, 9)
    return with_channels(smooth_values(shape), smooth_values(shape, 1.0)[::-1].copy(),
                         np.cos(smooth_values(shape, 2.0)))  # fmt: skip


def test_a_hidden_channel_or_one_of_weight_zero_adds_nothing():
    volume = three_channels()
    two = UniformVolume(
        volume.values, spacing=volume.spacing, channels=ChannelSet(volume.channels.values[:2])
    )
    camera = Camera.orbit(volume.bounds, 30, 20)
    expected, _ = render(two, ChannelTransferFunction([BASE, OTHER], [1.0, 0.7]), camera, 16)
    hidden, renderer = render(volume, ChannelTransferFunction([BASE, OTHER, THIRD], [1.0, 0.7, 1.0],
                                                              [True, True, False]), camera, 16)  # fmt: skip
    zero, _ = render(volume, ChannelTransferFunction([BASE, OTHER, THIRD], [1.0, 0.7, 0.0]), camera, 16)
    shown, _ = render(volume, ChannelTransferFunction([BASE, OTHER, THIRD], [1.0, 0.7, 1.0]), camera, 16)
    assert np.array_equal(hidden, expected) and np.array_equal(zero, expected)
    assert np.abs(shown - expected).max() > 0.05
    assert renderer.last_frame.counters["channels_drawn"] == 2


def test_hiding_every_channel_draws_nothing():
    volume = three_channels()
    tf = ChannelTransferFunction([BASE, OTHER, THIRD], visible=[False, False, False])
    image, renderer = render(volume, tf, Camera.orbit(volume.bounds, 20, 30), 12)
    assert np.all(image == 0.0) and renderer.last_frame.counters["channels_drawn"] == 0


def halved_unit(tf: TransferFunction1D) -> TransferFunction1D:
    """`tf` with twice its extinction: tau = -ln(1 - a) / d_u, so half the unit distance."""
    return TransferFunction1D(tf.color_points, tf.opacity_points, tf.opacity_unit_distance / 2.0)


def test_a_weight_of_two_is_the_tf_with_twice_the_extinction():
    volume = three_channels()
    camera = Camera.orbit(volume.bounds, 30, 20)
    plain = UniformVolume(volume.channels.values[1], spacing=volume.spacing)
    expected, _ = render(plain, halved_unit(OTHER), camera, 16, options={"tolerance": 1e-6})
    alone, _ = render(volume, ChannelTransferFunction([BASE, OTHER, THIRD], [0.0, 2.0, 0.0]), camera, 16,
                      options={"tolerance": 1e-6})  # fmt: skip
    assert expected[..., 3].max() > 0.5 and np.abs(alone - expected).max() < 1e-5
    weighted, _ = render(volume, ChannelTransferFunction([BASE, OTHER, THIRD], [1.0, 2.0, 0.5]), camera, 16)
    scaled, _ = render(volume, ChannelTransferFunction([BASE, halved_unit(OTHER), THIRD], [1.0, 1.0, 0.5]),
                       camera, 16)  # fmt: skip
    assert np.abs(weighted - scaled).max() < 1e-9


# ------------------------------------------------------------------------ the brute force
OFFSETS = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0), (0, 0, 1), (1, 0, 1), (0, 1, 1), (1, 1, 1)]


def brute_force(volume, tf, camera, n, samples=20000):
    """The channel model integrated along every pixel ray with `samples` midpoints (float64 numpy);
    a channel with a non-finite corner in a cell adds nothing there."""
    origins, dirs, t0, t1, _ = pixel_kept_intervals(camera, n, n, volume.bounds)
    channels = volume.channels.values.astype(np.float64)
    org, sp = np.asarray(volume.origin), np.asarray(volume.spacing)
    dims = np.array(channels.shape[1:][::-1])
    out = np.zeros((n, n, 4))
    for y, x in np.ndindex(n, n):
        if not t1[y, x] > t0[y, x]:
            continue
        dt = (t1[y, x] - t0[y, x]) / samples
        t = t0[y, x] + (np.arange(samples) + 0.5) * dt
        u = (origins[y, x] + t[:, None] * dirs[y, x] - org) / sp
        cell = np.clip(np.floor(u).astype(int), 0, dims - 2)
        fx, fy, fz = (u - cell).T
        i, j, k = cell.T
        corner_w = np.stack([(fx if a else 1 - fx) * (fy if b else 1 - fy) * (fz if c else 1 - fz)
                             for a, b, c in OFFSETS], axis=-1)  # fmt: skip
        tau, q = np.zeros(samples), np.zeros((samples, 3))
        for c in range(tf.count):
            cv = np.stack([channels[c, k + cz, j + by, i + ax] for ax, by, cz in OFFSETS], axis=-1)
            finite = np.isfinite(cv).all(axis=-1)
            s = np.where(finite, (np.nan_to_num(cv) * corner_w).sum(axis=-1), 0.0)
            one = ChannelTransferFunction([tf.tfs[c]], [tf.weights[c]], [tf.visible[c]])
            t_c, q_c = one.extinction_emission([s])
            tau += np.where(finite, t_c, 0.0)
            q += np.where(finite[:, None], q_c, 0.0)
        od = tau * dt
        trans = np.exp(-np.concatenate([[0.0], np.cumsum(od)[:-1]]))
        alpha = -np.expm1(-od)
        colour = np.where(tau[:, None] > 0, q / np.where(tau > 0, tau, 1.0)[:, None], 0.0)
        out[y, x, :3] = ((trans * alpha)[:, None] * colour).sum(axis=0)
        out[y, x, 3] = 1.0 - math.exp(-od.sum())
    return out


def test_the_brute_force_sums_the_models_extinction_and_emission():
    """The oracle's per-channel sum is `extinction_emission` of all channels where all are finite."""
    tf = ChannelTransferFunction([BASE, OTHER, THIRD], [1.0, 0.4, 2.0], [True, True, False])
    s = [np.linspace(-3, 5, 50), np.linspace(5, -2, 50), np.linspace(0, 1, 50)]
    tau, q = tf.extinction_emission(s)
    parts = [ChannelTransferFunction([tf.tfs[c]], [tf.weights[c]], [tf.visible[c]]).extinction_emission([s[c]])
             for c in range(3)]  # fmt: skip
    assert np.allclose(tau, sum(p[0] for p in parts), rtol=1e-14) and tau.max() > 1.0
    assert np.allclose(q, sum(p[1] for p in parts), rtol=1e-14)


@pytest.mark.parametrize("nan", [False, True], ids=["finite", "NaN in one channel"])
def test_random_channels_are_the_brute_force_integral_of_the_channel_model(nan):
    shape = (5, 6, 7)
    rng = np.random.default_rng(7)
    fields = [rng.uniform(-2.0, 4.0, shape), rng.uniform(-1.0, 3.0, shape), rng.uniform(0.0, 4.0, shape)]
    finite = with_channels(*fields, spacing=(1.0, 1.2, 0.9))
    if nan:
        fields[1][2, 3, 3] = np.nan
        fields[1][1, 1, 4] = np.inf
    volume = with_channels(*fields, spacing=(1.0, 1.2, 0.9))
    tf = ChannelTransferFunction([BASE, OTHER, THIRD], [1.0, 0.6, 1.7])
    camera = Camera.orbit(volume.bounds, 35, 25, zoom=1.4)
    n = 6
    image, _ = render(volume, tf, camera, n, options={"tolerance": 1e-8, "max_levels": 16})
    expected = brute_force(volume, tf, camera, n)
    assert expected[..., 3].max() > 0.5
    assert np.abs(image - expected).max() < 1e-6
    if nan:  # the rays do cross the cells of the non-finite points
        assert np.abs(expected - brute_force(finite, tf, camera, n, 2000)).max() > 1e-3


def test_nan_in_one_channel_makes_that_channel_transparent_in_its_cells_only():
    """The slab with channel 1 NaN on the plane of points i = 3: along x channel 1 is missing from
    cells 2 and 3, channel 0 is not: homogeneous layers (both | channel 0 | both) in a row."""
    volume, tf = channel_slab()
    values = volume.channels.values.copy()
    values[1, :, :, 3] = np.nan
    volume = UniformVolume(volume.values, spacing=volume.spacing, origin=volume.origin,
                           channels=ChannelSet(values))  # fmt: skip
    b = volume.bounds
    for sign in (1.0, -1.0):
        image, _ = render(volume, tf, axis_camera(b, 0, sign, 0.3 * (b[3] - b[2])), 8,
                          options={"tolerance": 1e-8})  # fmt: skip
        dx = SLAB_SPACING[0]
        (t0, t1), c0, c1 = slab_extinctions(), np.asarray(SLAB_COLOURS[0]), np.asarray(SLAB_COLOURS[1])
        both = ((t0 + t1) * 2 * dx, (t0 * c0 + t1 * c1) / (t0 + t1))
        layers = [both, (t0 * 2 * dx, c0), both]  # each 2 cells; symmetric, so the same from either side
        T, rgb = 1.0, np.zeros(3)
        for depth, colour in layers:
            rgb += T * -math.expm1(-depth) * colour
            T *= math.exp(-depth)
        assert np.abs(image - np.array([*rgb, 1.0 - T])).max() < 1e-7
        assert np.abs(image[0, 0] - channel_slab_rgba()).max() > 0.01


def test_a_cell_with_no_finite_drawn_channel_is_dropped():
    volume, tf = channel_slab()
    values = volume.channels.values.copy()
    values[:, :, :, 3] = np.nan  # both channels: cells 2 and 3 are empty
    volume = UniformVolume(volume.values, spacing=volume.spacing, origin=volume.origin,
                           channels=ChannelSet(values))  # fmt: skip
    b = volume.bounds
    image, _ = render(volume, tf, axis_camera(b, 0, 1.0, 0.3 * (b[3] - b[2])), 8, options={"tolerance": 1e-8})
    ell = SLAB_SPACING[0] * (SLAB_DIMS[0] - 1 - 2)
    assert np.abs(image - channel_slab_rgba(ell)).max() < 1e-7


# ------------------------------------------------------------------------------ refusals
@pytest.mark.parametrize(
    "settings, message",
    [
        ({"shade": True}, "shading"),
        ({"blend_mode": BlendMode.MAXIMUM}, "composite"),
        ({"blend_mode": BlendMode.AVERAGE}, "composite"),
        ({"clip": ClipRegion((ClipPlane((2.0, 0.0, 2.0), (1.0, 0.0, 0.0)),), cap=True)}, "cut faces"),
        ({"preintegration": True}, "pre-integration"),
    ],
)
def test_what_channels_are_not_drawn_with_is_refused_in_one_line(settings, message):
    volume, tf = channel_slab()
    renderer = ReferenceRenderer()
    renderer.set_volume(volume)
    renderer.set_transfer_function(tf)
    renderer.set_settings(RenderSettings(**settings))
    calls = []
    with pytest.raises(VolrenError, match=message) as err:
        renderer.render(Camera.orbit(volume.bounds, 20, 30), 8, 8, calls.append)
    assert "\n" not in str(err.value) and not calls


def test_a_2d_tf_is_no_channels_tf():
    tf2d = TransferFunction2D((0.0, 1.0), (0.0, 1.0), [TFWidget.box((0.2, 0.8), (0.0, 1.0), (1, 0, 0), 0.5)])
    with pytest.raises(VolrenError, match="1D"):
        ChannelTransferFunction([BASE, tf2d])  # type: ignore[list-item]


def test_a_channels_tf_needs_a_grid_with_as_many_channels():
    volume, tf = channel_slab()
    renderer = ReferenceRenderer()
    renderer.set_volume(UniformVolume(volume.values))
    renderer.set_transfer_function(tf)
    with pytest.raises(VolrenError, match="has no channels") as err:
        renderer.render(Camera(), 8, 8)
    assert "\n" not in str(err.value)
    renderer.set_volume(volume)
    renderer.set_transfer_function(ChannelTransferFunction([BASE, OTHER, THIRD]))
    with pytest.raises(VolrenError, match="has 2 channels"):
        renderer.render(Camera(), 8, 8)
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    renderer = ReferenceRenderer()
    renderer.set_volume(TetVolume(pts, np.array([[0, 1, 2, 3]]), np.ones(4)))
    with pytest.raises(VolrenError, match="channels"):
        renderer.set_transfer_function(tf)
    assert ReferenceRenderer.capabilities.kinds["uniform"].channels  # type: ignore[index]
    assert not ReferenceRenderer.capabilities.kinds["tet"].channels  # type: ignore[index]


# --------------------------------------------------------------------------- frame rules
def test_progress_rises_to_one_over_the_blocks_of_rows() -> None:
    volume, tf = channel_slab()
    renderer = ReferenceRenderer()
    renderer.set_volume(volume)
    renderer.set_transfer_function(tf)
    calls: list[float] = []
    renderer.render(Camera.orbit(volume.bounds, 20, 30), 16, 32, calls.append)
    assert len(calls) > 4 and calls == sorted(calls) and calls[-1] == 1.0


def test_a_weight_edited_between_frames_is_drawn_as_by_a_fresh_renderer():
    volume = three_channels()
    tf = ChannelTransferFunction([BASE, OTHER, THIRD])
    camera = Camera.orbit(volume.bounds, 20, 30)
    before, renderer = render(volume, tf, camera, 12)
    tf.set_weight(0, 3.0)
    tf.set_visible(2, False)
    renderer.render(camera, 12, 12)
    after = renderer.last_rgba64
    fresh, _ = render(volume, tf, camera, 12)
    assert np.abs(after - before).max() > 0.05
    assert np.array_equal(after, fresh)


def test_rays_that_do_not_converge_are_counted_and_warned_of_at_the_caller():
    volume = three_channels()
    renderer = ReferenceRenderer()
    renderer.set_volume(volume)
    renderer.set_transfer_function(ChannelTransferFunction([BASE, OTHER, THIRD]))
    renderer.set_settings(RenderSettings(options={"tolerance": 1e-14, "max_levels": 2}))
    with pytest.warns(VolrenWarning, match="did not converge") as caught:
        renderer.render(Camera.orbit(volume.bounds, 20, 30), 8, 8)
    assert caught[0].filename == __file__
    assert renderer.last_frame.counters["unconverged_rays"] > 0
