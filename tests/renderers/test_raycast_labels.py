"""raycast on label volumes (`march_labels`): the label model of `volren.model.labels`, checked
against its float64 oracle, the plain march, and closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest

from volren.errors import VolrenError
from volren.kernels.label_sample import label_sample
from volren.kernels.mixed_inputs import LabelClassification
from volren.model import BlendMode, Camera, RenderSettings, TransferFunction1D, UniformVolume
from volren.model.clip_region import ClipRegion
from volren.model.labels import LabelMap, LabelStyle, LabelTransferFunction, cell_classes, cell_label_weights
from volren.renderers.raycast import march_native
from volren.renderers.raycast.renderer import MAX_CLASSES_PER_BRICK, RaycastRenderer

TF = TransferFunction1D([[0.0, 1.0, 1.0, 1.0], [1.0, 1.0, 0.5, 0.2]], [[0.0, 0.0], [0.2, 0.05], [1.0, 0.3]])
SIZE = 48


def _blob(n: int = 28) -> tuple[np.ndarray, np.ndarray]:
    """A Gaussian blob and labels: a sphere (3) in a background (0), a slab (1, 4 inside the sphere)."""
    z, y, x = np.mgrid[0:n, 0:n, 0:n].astype(float)
    r = np.sqrt((x - n / 2) ** 2 + (y - n / 2) ** 2 + (z - n / 2) ** 2)
    labels = (r < n / 3).astype(np.uint8) * 3 + (x < n / 4)
    return np.exp(-((r / (n / 3)) ** 2)), labels


def _renderer(volume: UniformVolume, tf, **options) -> RaycastRenderer:
    renderer = RaycastRenderer()
    renderer.set_volume(volume)
    renderer.set_settings(RenderSettings(step=0.5, preintegration=False, options=options))
    renderer.set_transfer_function(tf)
    return renderer


def _camera(volume: UniformVolume) -> Camera:
    return Camera.orbit(volume.bounds, 30.0, 20.0)


def test_labels_that_all_draw_alike_give_the_plain_march() -> None:
    values, labels = _blob()
    volume = UniformVolume(values, labels=LabelMap(labels))
    with march_native.numba_only():
        plain = _renderer(volume, TF).render(_camera(volume), SIZE, SIZE)
    labelled = _renderer(volume, LabelTransferFunction(TF)).render(_camera(volume), SIZE, SIZE)
    assert plain[..., 3].max() > 0.3
    np.testing.assert_allclose(labelled, plain, atol=1e-6)


def test_a_sample_is_the_models_blend_of_its_corners_classes() -> None:
    """At points of cells whose corners hold two visible labels and a hidden one, the kernel's
    segment equals DESIGN.md's alpha = 1 - exp(-tau h), colour q / tau, with tau and q from the
    float64 oracle (`LabelTransferFunction.extinction_emission` over `cell_label_weights`)."""
    rng = np.random.default_rng(3)
    labels = rng.choice(np.array([0, 2, 5], np.uint8), size=(4, 4, 4))
    values = rng.uniform(0.0, 1.0, size=(4, 4, 4))
    tf = LabelTransferFunction(
        TF, {2: LabelStyle(color=(0.1, 0.9, 0.2)), 5: LabelStyle(color=(0.8, 0.1, 0.1), opacity=2.5),
             0: LabelStyle(visible=False)},
    )  # fmt: skip
    classes = tf.classes(5)
    n, h, lo, hi = 4096, 0.7, 0.0, 1.0
    post = np.zeros((len(classes.tfs), n, 4))
    for c, class_tf in enumerate(classes.tfs):
        rgb, a = class_tf.sample(np.linspace(lo, hi, n))
        post[c, :, :3] = rgb
        post[c, :, 3] = -np.expm1(h * np.log1p(-np.minimum(a, 1 - 1e-6)))
    table = LabelClassification(
        labels, classes.lookup, cell_classes(labels, classes.lookup), post, h, lo, (n - 1) / (hi - lo)
    )
    for _ in range(40):
        p = rng.uniform(0.0, 2.999, size=3)
        r, g, b, a = label_sample(values, table, p[0], p[1], p[2], h)
        i, j, k = (int(v) for v in p)
        f = p - np.floor(p)
        corners = [labels[k + (q >> 2), j + ((q >> 1) & 1), i + (q & 1)] for q in range(8)]
        weights = cell_label_weights(np.array(corners), f[0], f[1], f[2])
        cell = values[k : k + 2, j : j + 2, i : i + 2]
        s = (
            cell[0, 0, 0] * (1 - f[0]) * (1 - f[1]) * (1 - f[2]) + cell[0, 0, 1] * f[0] * (1 - f[1]) * (1 - f[2])
            + cell[0, 1, 0] * (1 - f[0]) * f[1] * (1 - f[2]) + cell[0, 1, 1] * f[0] * f[1] * (1 - f[2])
            + cell[1, 0, 0] * (1 - f[0]) * (1 - f[1]) * f[2] + cell[1, 0, 1] * f[0] * (1 - f[1]) * f[2]
            + cell[1, 1, 0] * (1 - f[0]) * f[1] * f[2] + cell[1, 1, 1] * f[0] * f[1] * f[2]
        )  # fmt: skip
        tau, q = tf.extinction_emission(s, weights)
        alpha = -math.expm1(-float(tau) * h)
        want = (np.asarray(q) / float(tau) * alpha).tolist() + [alpha] if tau > 0 else [0.0] * 4
        np.testing.assert_allclose([r, g, b, a], want, atol=2e-5)


def test_a_label_slab_absorbs_over_its_blended_length() -> None:
    """A constant field, label 1 from x = 5 on and a hidden label 0 before: along x the weight of
    label 1 ramps from 0 at x = 4 to 1 at x = 5, so a ray crosses tau over (nx - 1 - 5) + 1/2 voxels.
    The label of one corner instead (x >= 5 only) would absorb over half a voxel less."""
    nx = 12
    values = np.ones((6, 6, nx))
    labels = np.zeros((6, 6, nx), np.uint8)
    labels[:, :, 5:] = 1
    volume = UniformVolume(values, labels=LabelMap(labels))
    base = TransferFunction1D.constant(0.2, (0.3, 0.6, 0.9))
    tf = LabelTransferFunction(base, {0: LabelStyle(visible=False)})
    camera = Camera.orbit(volume.bounds, 90.0, 0.0, parallel=True)
    renderer = _renderer(volume, tf, depth_offsets="midpoint")
    image = renderer.render(camera, 16, 16)
    tau = -math.log(1 - 0.2)
    alpha = 1 - math.exp(-tau * ((nx - 1 - 5) + 0.5))
    centre = image[8, 8]
    assert abs(centre[3] - alpha) < 2e-3  # the midpoint rule across the ramp's two kinks
    np.testing.assert_allclose(centre[:3], np.array([0.3, 0.6, 0.9]) * centre[3], atol=1e-5)
    assert abs(centre[3] - (1 - math.exp(-tau * (nx - 1 - 5)))) > 0.01


@pytest.mark.parametrize("many", [False, True])
def test_skipping_changes_no_pixel_and_hidden_labels_cost_no_samples(many: bool) -> None:
    values, labels = _blob()
    if many:  # more classes than are classified brick by brick: a label per z plane, another in the sphere
        labels = (labels == 3) * 100 + np.arange(labels.shape[0])[:, None, None]
    volume = UniformVolume(values, labels=LabelMap(labels))
    tf = LabelTransferFunction.for_labels(TF, volume.labels)
    assert (len(tf.classes(volume.labels.max_label).tfs) > MAX_CLASSES_PER_BRICK) == many
    hidden = [label for label in volume.labels.present if (label % 100 < 14 if many else label % 3 != 0)]
    tf.hide(hidden)
    camera = _camera(volume)
    skipped = _renderer(volume, tf)
    image = skipped.render(camera, SIZE, SIZE)
    full = _renderer(volume, tf, empty_space_skipping=False)
    assert np.array_equal(image, full.render(camera, SIZE, SIZE))
    assert skipped.last_frame.counters["samples"] < full.last_frame.counters["samples"]
    assert image[..., 3].max() > 0.1
    tf.hide(volume.labels.present)
    nothing = _renderer(volume, tf)
    assert not nothing.render(camera, SIZE, SIZE).any()
    assert nothing.last_frame.counters["samples"] == 0


def test_a_hidden_background_shows_the_labelled_object_alone() -> None:
    values, labels = _blob()
    volume = UniformVolume(values, labels=LabelMap(labels))
    tf = LabelTransferFunction(TF, {label: LabelStyle(visible=False) for label in (0, 1, 4)})
    tf.set_style(3, LabelStyle(color=(0.0, 1.0, 0.0)))
    image = _renderer(volume, tf).render(_camera(volume), SIZE, SIZE)
    shown = image[..., 3] > 0.05
    assert shown.any()
    assert np.all(image[shown][:, 0] < 1e-6) and np.all(image[shown][:, 2] < 1e-6)  # green only


def test_refused_without_labels_with_other_blends_and_pre_integration() -> None:
    values, labels = _blob(12)
    tf = LabelTransferFunction(TF)
    bare = _renderer(UniformVolume(values), tf)
    with pytest.raises(VolrenError, match="has no labels"):
        bare.render(Camera.orbit(bare.volume.bounds), 8, 8)
    volume = UniformVolume(values, labels=LabelMap(labels))
    renderer = _renderer(volume, tf)
    renderer.set_settings(RenderSettings(preintegration=True))
    with pytest.raises(VolrenError, match="pre-integration with label volumes"):
        renderer.render(_camera(volume), 8, 8)
    renderer.set_settings(RenderSettings(preintegration=False, blend_mode=BlendMode.MAXIMUM))
    with pytest.raises(VolrenError, match="composite only"):
        renderer.render(_camera(volume), 8, 8)
    lo, hi = volume.bounds[0], volume.bounds[1]
    crop = ClipRegion(box=(lo, (lo + hi) / 2, *volume.bounds[2:]), cap=True)
    renderer.set_settings(RenderSettings(preintegration=False, clip=crop))
    with pytest.raises(VolrenError, match="cut faces"):
        renderer.render(_camera(volume), 8, 8)


@pytest.mark.skipif(not march_native.vector_path(), reason="the C march does not build here")
def test_the_c_march_draws_labels_as_numba_does() -> None:
    values, labels = _blob()
    for volume in (UniformVolume(values, labels=LabelMap(labels)),
                   UniformVolume((values * 255).astype(np.uint8), labels=LabelMap(labels.astype(np.uint16) * 300))):  # fmt: skip
        tf = LabelTransferFunction.for_labels(
            TransferFunction1D.ramp(*volume.value_range, 0.4), volume.labels
        )
        tf.hide([0])
        renderer = _renderer(volume, tf, termination_alpha=0.95)
        camera = _camera(volume)
        c_image = renderer.render(camera, SIZE, SIZE)
        c_counts = dict(renderer.last_frame.counters)
        with march_native.numba_only():
            numba_image = renderer.render(camera, SIZE, SIZE)
        assert c_image[..., 3].max() > 0.1
        np.testing.assert_allclose(c_image, numba_image, atol=2e-6)
        for name in ("samples", "segments_skipped", "rays_terminated"):
            assert abs(c_counts[name] - renderer.last_frame.counters[name]) <= 0.001 * max(c_counts[name], 1)
