"""The reference renderer with 2D transfer functions, against exact oracles.

(a) a 2D TF that depends on the value alone renders as the equivalent 1D TF does (the 1D path is
the oracle); (b) on a linear ramp |grad s| is one constant G, so a box whose gradient interval
excludes G draws nothing and one including it draws the 1D image (closed forms too); (c) on a
constant block grad s = 0, so every widget acts with its value at g = 0.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.renderers.test_reference import (
    axis_camera,
    grid,
    optical_depth_linear_opacity,
    render,
)
from volren.app.core.tf_seeding import seeded_2d
from volren.errors import VolrenError
from volren.model import (
    Camera,
    RenderSettings,
    TetVolume,
    TFWidget,
    TransferFunction1D,
    TransferFunction2D,
    UniformVolume,
)
from volren.model.colormaps import VIRIDIS, color_stops
from volren.renderers.reference import ReferenceRenderer
from volren.renderers.reference.tf2d import eval_tf2d, pack_tf2d
from volren.samples import marschner_lobb
from volren.testing.oracles import box_path_lengths
from volren.testing.reference_images import reference_image, scene_key

RED, BLUE, WHITE = (1.0, 0.0, 0.0), (0.0, 0.0, 1.0), (1.0, 1.0, 1.0)


def random_volume():
    return UniformVolume(np.random.default_rng(3).random((7, 6, 8)), spacing=(1.0, 0.8, 1.1))


def test_kernel_evaluation_matches_the_model():
    tf = TransferFunction2D(
        (-1.0, 2.0),
        (0.0, 3.0),
        [
            TFWidget.gaussian((0.5, 1.0), (0.3, 0.7), (0.9, 0.2, 0.1), 0.6),
            TFWidget.box((0.2, 0.8), (0.5, 2.0), (0.1, 0.8, 0.3), 0.4),
            TFWidget.triangle(1.0, 0.5, 2.5, (0.2, 0.3, 1.0), 0.9),
        ],
    )
    packed = pack_tf2d(tf)
    rng = np.random.default_rng(0)
    s = np.concatenate([rng.uniform(-2, 3, 400), [1.0, 1.0, 0.2, 0.8, np.nan, 0.5]])
    g = np.concatenate([rng.uniform(-1, 4, 400), [0.0, 2.5, 0.5, 2.0, 1.0, np.inf]])
    rgb, alpha = tf.sample(s, g)
    got = np.array([eval_tf2d(packed, a, b) for a, b in zip(s, g)])
    np.testing.assert_allclose(got[:, :3], rgb, atol=1e-15, rtol=0)
    np.testing.assert_allclose(got[:, 3], alpha, atol=1e-15, rtol=0)


def test_kernel_evaluates_1d_widgets_as_the_model():
    stepped = TransferFunction1D([[0, 1, 0, 0], [0.5, 0, 1, 0], [0.5, 0, 0, 1], [1.5, 1, 1, 1]],
                                 [[0.2, 0], [0.6, 0.7], [1.2, 0.1]])  # fmt: skip
    tinted = TFWidget("1d", (0.5, 0.8, 1.0), 0.7, gradient_range=(1.0, 3.0), color_points=[[0, 0.2, 0.3, 0.4]],
                      opacity_points=[[0.3, 0], [0.9, 1]])  # fmt: skip
    gaussian = TFWidget.gaussian((0.5, 1.0), (0.3, 0.7), (0.9, 0.2, 0.1), 0.6)
    tf = TransferFunction2D(
        (-1.0, 2.0), (0.0, 3.0), [gaussian, TFWidget.from_1d(stepped, (0.5, 2.0)), tinted]
    )
    packed = pack_tf2d(tf)
    rng = np.random.default_rng(1)
    s = np.concatenate([rng.uniform(-2, 3, 600), [0.1, 5.0, 0.5, 1.2]])
    g = np.concatenate([rng.uniform(-1, 4, 600), [0.7, 2.5, 1.0, 0.2]])  # transparent points in bands too
    rgb, alpha = tf.sample(s, g)
    got = np.array([eval_tf2d(packed, a, b) for a, b in zip(s, g)])
    np.testing.assert_allclose(got[:, :3], rgb, atol=1e-15, rtol=0)
    np.testing.assert_allclose(got[:, 3], alpha, atol=1e-15, rtol=0)


# ----------------------------------------------------------------------- (a) value-only 2D TFs
@pytest.mark.parametrize("shade", [False, True])
def test_the_2d_tf_made_from_a_1d_tf_renders_the_1d_image(shade):
    """What the editor's "Use a 2D transfer function" makes of a viridis ramp draws what the ramp
    draws: both converge to the reference's tolerance (1e-5 per ray), so they agree to about it."""
    vol = marschner_lobb(17)
    lo, hi = vol.value_range
    tf1 = TransferFunction1D(
        color_stops(VIRIDIS, lo, hi), [[lo, 0.0], [lo + 0.1 * (hi - lo), 0.0], [hi, 0.6]], 0.1
    )
    tf2 = seeded_2d(tf1, (lo, hi), 1.0)  # gradients above 1 clamp to the top of the band
    cam = Camera.orbit(vol.bounds, 30, 20)
    img1, _ = render(vol, tf1, cam, 24, shade=shade)
    img2, r2 = render(vol, tf2, cam, 24, shade=shade)
    assert r2.last_frame.counters["unconverged_rays"] == 0 and img1[..., 3].max() > 0.9
    assert np.sqrt(np.mean((img2 - img1) ** 2)) < 3e-6 and np.abs(img2 - img1).max() < 2e-5


def two_boxes(gmax: float) -> tuple[TransferFunction2D, TransferFunction1D]:
    """Two boxes over every gradient, and the 1D TF with the same steps in value."""
    tf2 = TransferFunction2D(
        (0.0, 1.0),
        (0.0, gmax),
        [TFWidget.box((0.2, 0.45), (0.0, gmax), RED, 0.3), TFWidget.box((0.6, 0.8), (0.0, gmax), BLUE, 0.7)],
        opacity_unit_distance=1.5,
    )
    opacity = [
        [0, 0],
        [0.2, 0],
        [0.2, 0.3],
        [0.45, 0.3],
        [0.45, 0],
        [0.6, 0],
        [0.6, 0.7],
        [0.8, 0.7],
        [0.8, 0],
    ]
    tf1 = TransferFunction1D([[0.45, 1, 0, 0], [0.45, 0, 0, 1]], opacity, opacity_unit_distance=1.5)
    return tf2, tf1


@pytest.mark.parametrize("shade", [False, True])
def test_a_value_only_2d_tf_renders_as_the_1d_tf(shade):
    vol = random_volume()
    cam = Camera.orbit(vol.bounds, 40, 25)
    # gmax below the largest |grad s|: larger gradients are clamped to gmax, still in the boxes
    tf2, tf1 = two_boxes(gmax=0.5)
    img2, r2 = render(vol, tf2, cam, 20, shade=shade)
    img1, _ = render(vol, tf1, cam, 20, shade=shade)
    assert r2.last_frame.counters["unconverged_rays"] == 0 and img1[..., 3].max() > 0.3
    # unshaded both integrate piecewise-constant media exactly; shaded both converge to tol 1e-5
    assert np.abs(img2 - img1).max() < (1e-10 if not shade else 5e-5)


# ------------------------------------------------------------------------------ (b) linear ramp
RAMP_SLOPE = 2.5  # s = 2.5 x: central differences give grad s = (2.5, 0, 0) exactly


def ramp():
    return grid(lambda x, y, z: RAMP_SLOPE * x, (6, 4, 3), (0.5, 1.2, 0.9))


def ramp_camera(vol):
    b = vol.bounds
    return axis_camera(b, (-1, 0, 0), 0.35 * min(b[3] - b[2], b[5] - b[4]), (0, 0, 1))


@pytest.mark.parametrize("g_interval, drawn", [((0.0, 2.0), False), ((3.0, 6.0), False), ((2.0, 3.0), True)])
def test_ramp_box_by_gradient(g_interval, drawn):
    vol = ramp()
    cam = ramp_camera(vol)
    a, d = 0.4, 0.3
    tf2 = TransferFunction2D((0.0, 7.0), (0.0, 6.0), [TFWidget.box((1.0, 4.0), g_interval, RED, a)], d)
    img, r = render(vol, tf2, cam, 6)
    if not drawn:
        assert np.all(img == 0)
        return
    # s runs from 1 to 4 over x in [0.4, 1.6]: a homogeneous slab 1.2 long
    alpha = 1 - (1 - a) ** (1.2 / d)
    np.testing.assert_allclose(img[..., 3], alpha, atol=1e-9, rtol=0)
    np.testing.assert_allclose(img[..., 0], alpha, atol=1e-9, rtol=0)
    tf1 = TransferFunction1D([[0, 1, 0, 0]], [[1, 0], [1, a], [4, a], [4, 0]], d)
    img1, _ = render(vol, tf1, cam, 6)
    assert np.abs(img - img1).max() < 1e-10


def test_ramp_triangle_is_a_1d_tent_at_the_ramp_gradient():
    """At g = 2.5 a triangle with half_width 2 at gradient_max 5 is h = 1 wide: a(s) is the
    tent 0.8 (1 - |s - 3|), piecewise linear, which the 1D path and a closed form integrate."""
    vol = ramp()
    cam = ramp_camera(vol)
    d = 0.5
    tf2 = TransferFunction2D((0.0, 7.0), (0.0, 6.0), [TFWidget.triangle(3.0, 2.0, 5.0, WHITE, 0.8)], d)
    img, r = render(vol, tf2, cam, 5)
    assert r.last_frame.counters["unconverged_rays"] == 0
    tent = [(2.0, 0.0), (3.0, 0.8), (4.0, 0.0)]
    # optical depth: the integral over x of -ln(1 - a(2.5 x)) / d, with ds = 2.5 dx
    depth = optical_depth_linear_opacity(tent, 2.0, 4.0) / RAMP_SLOPE / d
    assert abs(img[..., 3] - (1 - math.exp(-depth))).max() < 1e-5
    img1, _ = render(vol, TransferFunction1D([[0, 1, 1, 1]], [list(p) for p in tent], d), cam, 5)
    assert np.abs(img - img1).max() < 1e-5


def test_ramp_with_shading_matches_the_1d_path():
    """A constant gradient shades every sample alike, so shading keeps both exact."""
    vol = ramp()
    cam = Camera.orbit(vol.bounds, 35, 20)
    tf2 = TransferFunction2D(
        (0.0, 7.0), (0.0, 6.0), [TFWidget.box((1.0, 5.0), (2.0, 3.0), (0.9, 0.6, 0.3), 0.5)]
    )
    tf1 = TransferFunction1D([[0, 0.9, 0.6, 0.3]], [[1, 0], [1, 0.5], [5, 0.5], [5, 0]])
    img2, _ = render(vol, tf2, cam, 16, shade=True, specular=0.4)
    img1, _ = render(vol, tf1, cam, 16, shade=True, specular=0.4)
    assert img1[..., 3].max() > 0.3 and np.abs(img2 - img1).max() < 1e-9


# --------------------------------------------------------------------------- (c) constant block
@pytest.mark.parametrize(
    "widget, opacity",
    [
        (TFWidget.box((6.0, 8.0), (0.0, 1.0), RED, 0.35), 0.35),
        (TFWidget.box((6.0, 8.0), (0.5, 1.0), RED, 0.35), 0.0),  # g = 0 is below the box
        (TFWidget.triangle(7.0, 1.0, 2.0, RED, 0.6), 0.6),  # the apex: s = s0 at g = 0
        (TFWidget.triangle(7.5, 1.0, 2.0, RED, 0.6), 0.0),  # at g = 0 the triangle is its apex only
        (TFWidget.gaussian((7.5, 0.5), (1.0, 0.5), RED, 0.8), 0.8 * math.exp(-0.125 - 0.5)),
    ],
    ids=["box-at-0", "box-above-0", "triangle-apex", "triangle-off-apex", "gaussian"],
)
def test_constant_block_uses_each_widget_at_zero_gradient(widget, opacity):
    vol = UniformVolume(np.full((4, 6, 5), 7.0), spacing=(0.7, 1.3, 0.4), origin=(-1.0, 2.0, 0.5))
    d = 0.8
    tf = TransferFunction2D((0.0, 10.0), (0.0, 2.0), [widget], d)
    cam = Camera.orbit(vol.bounds, 30, 20, zoom=1.3)
    img, r = render(vol, tf, cam, 24, 20)
    L = box_path_lengths(cam, 24, 20, vol.bounds)
    alpha = 1 - (1 - opacity) ** (L / d)
    np.testing.assert_allclose(img[..., 3], alpha, atol=1e-9, rtol=0)
    np.testing.assert_allclose(img[..., 0], alpha, atol=1e-9, rtol=0)
    assert np.all(img[..., 1:3] == 0) and r.last_frame.counters["unconverged_rays"] == 0


# ----------------------------------------------------------------------- convergence, contract
def test_smooth_widgets_converge_independently_of_the_initial_step():
    vol = random_volume()
    tf = TransferFunction2D(
        (0.0, 1.0),
        (0.0, 1.0),
        [
            TFWidget.gaussian((0.5, 0.3), (0.1, 0.15), (1.0, 0.5, 0.2), 0.6),
            TFWidget.triangle(0.3, 0.15, 0.6, (0.1, 0.4, 1.0), 0.8),
        ],
        opacity_unit_distance=2.0,
    )
    cam = Camera.orbit(vol.bounds, 40, 25)
    coarse, r = render(vol, tf, cam, 20, step=2.0)
    fine, _ = render(vol, tf, cam, 20, step=0.25)
    assert r.last_frame.counters["unconverged_rays"] == 0 and coarse[..., 3].max() > 0.3
    assert np.abs(coarse - fine).max() < 3e-5


def test_2d_tf_is_refused_on_tets_and_outside_composite():
    tf = two_boxes(1.0)[0]
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    r = ReferenceRenderer()
    r.set_volume(TetVolume(pts, np.array([[0, 1, 2, 3]]), np.ones(4)))
    with pytest.raises(
        VolrenError, match="^renderer reference does not support 2D transfer functions on tet volumes$"
    ):
        r.set_transfer_function(tf)
    r = ReferenceRenderer()
    vol = random_volume()
    r.set_volume(vol)
    r.set_transfer_function(tf)
    r.set_settings(RenderSettings(blend_mode="maximum"))
    with pytest.raises(
        VolrenError, match="has no maximum blend mode with 2D transfer functions on uniform volumes"
    ):
        r.render(Camera.orbit(vol.bounds), 4, 4)
    caps = ReferenceRenderer.capabilities
    assert caps.unsupported_reason("uniform", 2, RenderSettings(shade=True)) is None
    assert "2D TF blend composite" in caps.describe()


def test_reference_cache_keys_on_the_2d_tf(tmp_path):
    vol = ramp()
    cam = ramp_camera(vol)
    tf = TransferFunction2D((0.0, 7.0), (0.0, 6.0), [TFWidget.box((1.0, 4.0), (2.0, 3.0), RED, 0.4)], 0.3)
    settings = RenderSettings()
    key = scene_key(vol, tf, cam, 6, 6, settings)
    assert key == scene_key(vol, tf.copy(), cam, 6, 6, settings)
    other = tf.copy()
    other.replace_widget(0, TFWidget.box((1.0, 4.0), (2.0, 3.5), RED, 0.4))
    assert scene_key(vol, other, cam, 6, 6, settings) != key
    first = reference_image(vol, tf, cam, 6, 6, folder=tmp_path)
    assert (tmp_path / f"{key}.npy").exists() and first[..., 3].max() > 0.5
    assert np.array_equal(reference_image(vol, tf, cam, 6, 6, folder=tmp_path), first)


def test_nan_voxels_leave_a_finite_image():
    """Cells with a NaN corner are skipped; where only the gradient sees the NaN, |grad s| is NaN
    and the TF transparent (as `TransferFunction2D.sample` has it)."""
    values = np.random.default_rng(5).random((5, 6, 7))
    values[2, 3, 3] = np.nan
    vol = UniformVolume(values)
    tf = TransferFunction2D((0.0, 1.0), (0.0, 2.0), [TFWidget.gaussian((0.5, 0.5), (0.2, 0.4), WHITE, 0.7)])
    img, r = render(vol, tf, Camera.orbit(vol.bounds, 20, 10), 12, shade=True)
    assert np.isfinite(img).all() and img[..., 3].max() > 0.1
    assert r.last_frame.counters["unconverged_rays"] == 0
