"""The reference renderer with label volumes (`volren.model.labels`) against exact oracles.

The oracles never call the renderer's integration code: the plain reference (every label drawn with
the base TF is the plain model), closed forms of constant media whose label weight ramps linearly
over one cell, and a float64 brute-force integral of the label model along each ray from
`LabelTransferFunction.extinction_emission` and `cell_label_weights`.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from volren.errors import VolrenError, VolrenWarning
from volren.model import BlendMode, Camera, RenderSettings, TetVolume, TransferFunction1D, UniformVolume
from volren.model.clip_region import ClipPlane, ClipRegion
from volren.model.labels import LabelMap, LabelStyle, LabelTransferFunction, cell_label_weights
from volren.model.transfer_function_2d import TFWidget, TransferFunction2D
from volren.renderers.reference import ReferenceRenderer
from volren.testing.oracles import pixel_kept_intervals
from volren.testing.scenes import axis_camera

HIDDEN = LabelStyle(visible=False)
RED, GREEN = (1.0, 0.1, 0.1), (0.1, 0.9, 0.2)


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


def smooth_values(shape):
    z, y, x = np.mgrid[0 : shape[0], 0 : shape[1], 0 : shape[2]].astype(np.float64)
    return np.sin(x / 3.0) + np.cos(y / 4.0) + z / 8.0


def ball_labels(shape, centre, radius, inside, outside):
    z, y, x = np.mgrid[0 : shape[0], 0 : shape[1], 0 : shape[2]]
    d2 = (x - centre[0]) ** 2 + (y - centre[1]) ** 2 + (z - centre[2]) ** 2
    return np.where(d2 <= radius * radius, inside, outside).astype(np.uint8)


BASE = TransferFunction1D([[-2, 0.2, 0.3, 1.0], [1.0, 0.9, 0.1, 0.4], [4, 1.0, 0.8, 0.1]],
                          [[-1, 0.0], [1.2, 0.5], [4, 0.7]], 1.5)  # fmt: skip


# ------------------------------------------------------------------------- the plain model
@pytest.mark.parametrize("clip", [False, True], ids=["whole", "clip plane"])
def test_every_label_drawn_with_the_base_tf_is_the_plain_reference(clip):
    shape = (12, 13, 14)
    values = smooth_values(shape)
    values[5, 6, 3] = np.nan  # its eight cells are transparent in both
    labels = ball_labels(shape, (7, 6, 6), 4, 2, 1)
    labels[:, :, :3] = 0
    plain = UniformVolume(values, spacing=(1.0, 0.9, 1.1))
    labelled = UniformVolume(values, spacing=(1.0, 0.9, 1.1), labels=LabelMap(labels))
    camera = Camera.orbit(plain.bounds, 30, 20)
    region = ClipRegion((ClipPlane((7.0, 6.0, 6.0), (1.0, 0.4, -0.3)),)) if clip else ClipRegion()
    expected, _ = render(plain, BASE, camera, 32, clip=region, options={"tolerance": 1e-6})
    image, renderer = render(labelled, LabelTransferFunction(BASE), camera, 32, clip=region,
                             options={"tolerance": 1e-6})  # fmt: skip
    assert expected[..., 3].max() > 0.5 and (expected[..., 3] == 0).sum() > 50
    assert np.abs(image - expected).max() < 1e-5
    assert renderer.last_frame.counters["label_classes"] == 1


# ---------------------------------------------------------------------- the label weights
def slab_volume(nx=12, boundary=5, spacing=(0.8, 1.0, 1.1), value=0.5):
    """A constant field, label 1 at points i >= boundary and 0 below."""
    shape = (6, 7, nx)
    labels = np.zeros(shape, np.uint8)
    labels[:, :, boundary:] = 1
    return UniformVolume(
        np.full(shape, value), spacing=spacing, origin=(1.0, -2.0, 0.5), labels=LabelMap(labels)
    )


@pytest.mark.parametrize("sign", [1.0, -1.0], ids=["from +x", "from -x"])
def test_a_label_slab_is_the_closed_form_with_the_weight_ramping_over_one_cell(sign):
    nx, boundary = 12, 5
    volume = slab_volume(nx, boundary)
    opacity, unit = 0.3, 0.7
    tf = LabelTransferFunction(TransferFunction1D.constant(opacity, (0.9, 0.9, 0.9), unit),
                               {0: HIDDEN, 1: LabelStyle(color=GREEN)})  # fmt: skip
    b = volume.bounds
    camera = axis_camera(b, 0, sign, 0.3 * (b[3] - b[2]))
    image, _ = render(volume, tf, camera, 16, options={"tolerance": 1e-8})
    tau = -math.log(1.0 - opacity) / unit
    alpha = 1.0 - math.exp(-tau * volume.spacing[0] * ((nx - 1 - boundary) + 0.5))
    expected = np.array([GREEN[0] * alpha, GREEN[1] * alpha, GREEN[2] * alpha, alpha])
    assert np.abs(image - expected).max() < 1e-6


@pytest.mark.parametrize("radius", [9.6, 10.3, 11.5])
def test_a_ball_of_one_label_in_a_hidden_one_has_the_radius_of_its_points(radius):
    """No voxel stairs, no half-voxel shift: the label's weight is 1/2 about midway between the
    last point inside and the first outside, so the ball's silhouette (alpha-weighted area, an
    opaque TF whose unit distance is half the grid: rays through the middle are opaque, and a ray
    grazing the edge turns half opaque a little outside that surface) has the points' radius."""
    n_grid = 33
    shape = (n_grid, n_grid, n_grid)
    centre = (n_grid - 1) / 2.0
    labels = ball_labels(shape, (centre, centre, centre), radius, 3, 0)
    volume = UniformVolume(np.ones(shape), labels=LabelMap(labels))
    tf = LabelTransferFunction(TransferFunction1D.constant(1.0, (1.0, 0.8, 0.6), n_grid / 2.0), {0: HIDDEN})
    scale = 0.6 * n_grid
    n = 64
    image, _ = render(volume, tf, axis_camera(volume.bounds, 2, 1.0, scale), n)
    alpha = image[..., 3]
    pixel = 2.0 * scale / n
    area_radius = math.sqrt(alpha.sum() * pixel * pixel / math.pi)
    assert abs(area_radius - radius) < 0.5
    assert alpha.max() > 0.999 and alpha[0, 0] == 0.0
    assert np.allclose(image[..., :3], alpha[..., None] * (1.0, 0.8, 0.6), atol=1e-6)


def brute_force(volume, tf, camera, n, samples=20000):
    """The label model integrated along every pixel ray with `samples` midpoints (float64 numpy)."""
    origins, dirs, t0, t1, _ = pixel_kept_intervals(camera, n, n, volume.bounds)
    values, labels = volume.values, volume.labels.values
    org, sp = np.asarray(volume.origin), np.asarray(volume.spacing)
    dims = np.array(values.shape[::-1])
    out = np.zeros((n, n, 4))
    for y, x in np.ndindex(n, n):
        if not t1[y, x] > t0[y, x]:
            continue
        dt = (t1[y, x] - t0[y, x]) / samples
        t = t0[y, x] + (np.arange(samples) + 0.5) * dt
        u = (origins[y, x] + t[:, None] * dirs[y, x] - org) / sp
        cell = np.clip(np.floor(u).astype(int), 0, dims - 2)
        f = u - cell
        i, j, k = cell.T
        offsets = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0), (0, 0, 1), (1, 0, 1), (0, 1, 1), (1, 1, 1)]
        corners = np.stack([labels[k + c, j + b, i + a] for a, b, c in offsets], axis=-1)
        cv = np.stack([values[k + c, j + b, i + a] for a, b, c in offsets], axis=-1)
        fx, fy, fz = f.T
        corner_w = np.stack([(fx if a else 1 - fx) * (fy if b else 1 - fy) * (fz if c else 1 - fz)
                             for a, b, c in offsets], axis=-1)  # fmt: skip
        s = (cv * corner_w).sum(axis=-1)
        tau, q = tf.extinction_emission(s, cell_label_weights(corners, f[:, 0], f[:, 1], f[:, 2]))
        od = tau * dt
        trans = np.exp(-np.concatenate([[0.0], np.cumsum(od)[:-1]]))
        alpha = -np.expm1(-od)
        colour = np.where(tau[:, None] > 0, q / np.where(tau > 0, tau, 1.0)[:, None], 0.0)
        out[y, x, :3] = ((trans * alpha)[:, None] * colour).sum(axis=0)
        out[y, x, 3] = 1.0 - math.exp(-od.sum())
    return out


def test_mixed_cells_are_the_brute_force_integral_of_the_label_model():
    shape = (5, 6, 7)
    rng = np.random.default_rng(5)
    values = smooth_values(shape)
    labels = rng.choice(np.array([0, 1, 2, 4], np.uint8), size=shape, p=[0.3, 0.3, 0.3, 0.1])
    volume = UniformVolume(values, spacing=(1.0, 1.2, 0.9), labels=LabelMap(labels))
    own = TransferFunction1D([[0.0, 0.1, 0.2, 0.9], [2.0, 0.9, 0.6, 0.1]], [[0.0, 0.9], [2.5, 0.2]], 0.8)
    tf = LabelTransferFunction(
        BASE, {1: LabelStyle(color=RED, opacity=1.5), 2: LabelStyle(tf=own), 4: HIDDEN}
    )
    camera = Camera.orbit(volume.bounds, 35, 25, zoom=1.4)
    n = 6
    image, renderer = render(volume, tf, camera, n, options={"tolerance": 1e-8, "max_levels": 16})
    expected = brute_force(volume, tf, camera, n)
    assert expected[..., 3].max() > 0.5
    assert np.abs(image - expected).max() < 1e-6
    assert renderer.last_frame.counters["label_classes"] == 3


# ---------------------------------------------------------------------------- visibility
def test_hiding_every_label_draws_nothing():
    volume = slab_volume()
    tf = LabelTransferFunction(TransferFunction1D.constant(0.8), default=HIDDEN)
    image, renderer = render(volume, tf, Camera.orbit(volume.bounds, 20, 30), 24)
    assert np.all(image == 0.0)
    assert renderer.last_frame.counters["label_classes"] == 0


def test_two_labels_show_their_own_colours_where_only_they_are_crossed():
    nx, split = 12, 6
    shape = (5, 8, nx)
    labels = np.ones(shape, np.uint8)
    labels[:, :, split:] = 2
    opacity, unit = 0.25, 1.3
    volume = UniformVolume(np.full(shape, 2.0), labels=LabelMap(labels))
    tf = LabelTransferFunction(TransferFunction1D.constant(opacity, (1.0, 1.0, 1.0), unit),
                               {1: LabelStyle(color=RED), 2: LabelStyle(color=GREEN)})  # fmt: skip
    b = volume.bounds
    n = 24
    camera = axis_camera(b, 2, 1.0, 0.5 * (b[3] - b[2]))  # along z: each ray stays in one column of cells
    image, _ = render(volume, tf, camera, n, options={"tolerance": 1e-8})
    origins, _, t0, t1, _ = pixel_kept_intervals(camera, n, n, b)
    x = origins[..., 0]
    depth = np.maximum(t1 - t0, 0.0)
    alpha = 1.0 - (1.0 - opacity) ** (depth / unit)
    # label 2's weight along a ray is x - (split - 1) in the boundary cell (0 left of it, 1 right):
    # both labels have the same tau, so the colour is the weights' mix of theirs
    share = np.clip(x - (split - 1), 0.0, 1.0)[..., None]
    colour = (1.0 - share) * np.asarray(RED) + share * np.asarray(GREEN)
    expected = np.concatenate([alpha[..., None] * colour, alpha[..., None]], axis=-1)
    hit = depth > 0
    assert (hit & (share[..., 0] == 0)).sum() > 40 and (hit & (share[..., 0] == 1)).sum() > 40
    assert (hit & (share[..., 0] > 0.2) & (share[..., 0] < 0.8)).sum() > 10
    assert np.abs(image - expected).max() < 1e-6


# ------------------------------------------------------------------------------ refusals
@pytest.mark.parametrize(
    "settings, message",
    [
        ({"shade": True}, "shading"),
        ({"blend_mode": BlendMode.MAXIMUM}, "composite"),
        ({"blend_mode": BlendMode.AVERAGE}, "composite"),
        ({"clip": ClipRegion((ClipPlane((5.0, 3.0, 2.0), (1.0, 0.0, 0.0)),), cap=True)}, "cut faces"),
    ],
)
def test_what_labels_are_not_drawn_with_is_refused_in_one_line(settings, message):
    volume = slab_volume()
    renderer = ReferenceRenderer()
    renderer.set_volume(volume)
    renderer.set_transfer_function(LabelTransferFunction(TransferFunction1D.constant(0.5)))
    renderer.set_settings(RenderSettings(**settings))
    calls = []
    with pytest.raises(VolrenError, match=message) as err:
        renderer.render(Camera.orbit(volume.bounds, 20, 30), 8, 8, calls.append)
    assert "\n" not in str(err.value) and not calls


def test_a_2d_tf_is_no_base_for_labels():
    tf2d = TransferFunction2D((0.0, 1.0), (0.0, 1.0), [TFWidget.box((0.2, 0.8), (0.0, 1.0), (1, 0, 0), 0.5)])
    with pytest.raises(VolrenError, match="1D TF"):
        LabelTransferFunction(tf2d)  # type: ignore[arg-type]


def test_a_label_tf_needs_a_volume_with_labels_on_a_grid():
    tf = LabelTransferFunction(TransferFunction1D.constant(0.5))
    renderer = ReferenceRenderer()
    renderer.set_volume(UniformVolume(np.ones((4, 4, 4))))
    renderer.set_transfer_function(tf)
    with pytest.raises(VolrenError, match="has no labels") as err:
        renderer.render(Camera(), 8, 8)
    assert "\n" not in str(err.value)
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    mesh = TetVolume(pts, np.array([[0, 1, 2, 3]]), np.ones(4))
    renderer = ReferenceRenderer()
    renderer.set_volume(mesh)
    with pytest.raises(VolrenError, match="label volumes"):
        renderer.set_transfer_function(tf)
    assert ReferenceRenderer.capabilities.kinds["uniform"].labels  # type: ignore[index]
    assert not ReferenceRenderer.capabilities.kinds["tet"].labels  # type: ignore[index]


def test_progress_rises_to_one_over_the_blocks_of_rows() -> None:
    volume = slab_volume()
    renderer = ReferenceRenderer()
    renderer.set_volume(volume)
    renderer.set_transfer_function(LabelTransferFunction(TransferFunction1D.constant(0.5)))
    calls: list[float] = []
    renderer.render(Camera.orbit(volume.bounds, 20, 30), 16, 32, calls.append)
    assert len(calls) > 4 and calls == sorted(calls) and calls[-1] == 1.0


def test_a_style_edited_between_frames_is_drawn_as_by_a_fresh_renderer():
    volume = slab_volume()
    tf = LabelTransferFunction(TransferFunction1D.constant(0.4, (0.5, 0.5, 0.9)), {1: LabelStyle(color=RED)})
    camera = Camera.orbit(volume.bounds, 20, 30)
    before, renderer = render(volume, tf, camera, 16)
    tf.hide([1])
    renderer.render(camera, 16, 16)
    after = renderer.last_rgba64
    fresh, _ = render(volume, tf, camera, 16)
    assert np.abs(after - before).max() > 0.1
    assert np.array_equal(after, fresh)


def test_rays_that_do_not_converge_are_counted_and_warned_of_at_the_caller():
    shape = (6, 7, 8)
    volume = UniformVolume(smooth_values(shape), labels=LabelMap(ball_labels(shape, (4, 3, 3), 2, 2, 1)))
    renderer = ReferenceRenderer()
    renderer.set_volume(volume)
    renderer.set_transfer_function(LabelTransferFunction(BASE))
    renderer.set_settings(RenderSettings(options={"tolerance": 1e-14, "max_levels": 2}))
    with pytest.warns(VolrenWarning, match="did not converge") as caught:
        renderer.render(Camera.orbit(volume.bounds, 20, 30), 8, 8)
    assert caught[0].filename == __file__
    assert renderer.last_frame.counters["unconverged_rays"] > 0
