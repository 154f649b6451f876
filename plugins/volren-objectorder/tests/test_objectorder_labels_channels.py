"""The object-order plugin on label volumes and multi-channel volumes (the shared kernels
`volren.kernels.label_sample` and `channel_sample`): the same samples as a float64 ray caster of the
label and channel models, the plain image where the labels all draw alike or one channel is drawn,
hidden labels costing nothing, the kit's closed forms, and the refusals."""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

import numpy as np
import pytest
from volren_objectorder import ObjectOrderRenderer

from volren.errors import VolrenError
from volren.kernels.sample_placement import pixel_phases
from volren.model import BlendMode, Camera, UniformVolume
from volren.model.channels import ChannelTransferFunction
from volren.model.labels import LabelStyle, LabelTransferFunction, cell_label_weights
from volren.testing.channel_scenes import channel_scene, channel_slab, channel_slab_rgba
from volren.testing.label_scenes import label_scene, label_slab, label_slab_rgba
from volren.testing.reference_images import reference_image
from volren.testing.render_helpers import render_checked
from volren.testing.scenes import axis_camera

draw = partial(render_checked, ObjectOrderRenderer)
#: The largest table: its interpolation error (against the exact TFs of the oracles) stays below 1e-6.
FINE = {"classification_table": 65536}
#: objectorder's declared accuracy on uniform grids (its capabilities)
RMSE = ObjectOrderRenderer.capabilities.kinds["uniform"].accuracy.rmse

Sample = Callable[[np.ndarray, np.ndarray, np.ndarray], tuple[float, np.ndarray]]


def _float64_march(volume: UniformVolume, sample: Sample, camera: Camera, w: int, h_px: int, step: float,
                   offsets: np.ndarray) -> np.ndarray:  # fmt: skip
    """A ray caster in float64, pixel by pixel, at the CPU ray casters' samples (the middles of
    segments cut at (phase + j) steps, `volren.testing.oracles.midpoint_march`): `sample(base, f,
    idx)` gives (tau, q) of the model at index point idx (cell `base`, local f), each segment's
    alpha 1 - exp(-tau L) and colour q / tau, front to back."""
    origins, dirs = camera.pixel_rays(w, h_px)
    origins, dirs = origins.reshape(-1, 3), dirs.reshape(-1, 3)
    b = np.asarray(volume.bounds)
    lo, hi = b[0::2], b[1::2]
    with np.errstate(divide="ignore", invalid="ignore"):
        ta, tb = (lo - origins) / dirs, (hi - origins) / dirs
    t_in = np.where(dirs == 0, -np.inf, np.minimum(ta, tb)).max(axis=1)
    t_out = np.where(dirs == 0, np.inf, np.maximum(ta, tb)).min(axis=1)
    t0, t1 = np.maximum(t_in, 0.0), t_out
    hstep = step * volume.characteristic_length
    dims = np.asarray(volume.dimensions)
    out = np.zeros((len(origins), 4))
    for p in range(len(origins)):
        if not t1[p] - t0[p] > 0:
            continue
        j0 = np.floor(t0[p] / hstep)
        cuts = (offsets[p] + j0 + np.arange(0, int((t1[p] - t0[p]) / hstep) + 3)) * hstep
        cuts = cuts[(cuts > t0[p] + 1e-9 * hstep) & (cuts < t1[p] - 1e-9 * hstep)]
        ends = np.concatenate([[t0[p]], cuts, [t1[p]]])
        for a, e in zip(ends[:-1], ends[1:], strict=True):
            idx = (origins[p] + (a + e) / 2 * dirs[p] - np.asarray(volume.origin)) / np.asarray(
                volume.spacing
            )
            base = np.clip(np.floor(idx), 0, dims - 2).astype(int)
            tau, q = sample(base, np.clip(idx - base, 0, 1), idx)
            if tau <= 0.0:
                continue
            alpha = -np.expm1(-tau * (e - a))
            out[p, :3] += (1.0 - out[p, 3]) * alpha * q / tau
            out[p, 3] += (1.0 - out[p, 3]) * alpha
    return out.reshape(h_px, w, 4)


def _trilinear(values: np.ndarray, base: np.ndarray, f: np.ndarray) -> float:
    i, j, k = base
    cube = values[k : k + 2, j : j + 2, i : i + 2].astype(np.float64)
    x = cube[:, :, 0] + f[0] * (cube[:, :, 1] - cube[:, :, 0])
    y = x[:, 0] + f[1] * (x[:, 1] - x[:, 0])
    return float(y[0] + f[2] * (y[1] - y[0]))


def _label_sample(volume: UniformVolume, tf: LabelTransferFunction) -> Sample:
    """The label model at a point: its corners' labels weighted trilinearly (`cell_label_weights`)."""
    labels = volume.labels.values  # type: ignore[union-attr]

    def sample(base: np.ndarray, f: np.ndarray, idx: np.ndarray) -> tuple[float, np.ndarray]:
        i, j, k = base
        corners = np.array([labels[k + (q >> 2), j + ((q >> 1) & 1), i + (q & 1)] for q in range(8)])
        weights = cell_label_weights(corners, f[0], f[1], f[2])
        tau, q = tf.extinction_emission(_trilinear(volume.values, base, f), weights)
        return float(tau), q

    return sample


def _channel_sample(volume: UniformVolume, tf: ChannelTransferFunction) -> Sample:
    channels = volume.channels.values  # type: ignore[union-attr]

    def sample(base: np.ndarray, f: np.ndarray, idx: np.ndarray) -> tuple[float, np.ndarray]:
        tau, q = tf.extinction_emission([_trilinear(channels[c], base, f) for c in range(len(channels))])
        return float(tau), q

    return sample


@pytest.mark.parametrize("parallel", [True, False])
def test_labels_are_a_float64_ray_casters_samples(parallel):
    """Object order, octree skipping on, composites the samples of a float64 ray caster of the label
    model (RTVG section 16.5) at the same step and offsets (rays not stopped at termination_alpha)."""
    volume, tf = label_scene()
    camera = Camera.orbit(volume.bounds, 35, 25, zoom=1.2, parallel=parallel)
    w, h = 20, 16
    image, _ = draw(volume, tf, camera, (w, h), step=0.37, options={"depth_offsets": "random", "jitter_seed": 3,
                                                                   "hidden_volume_removal": False, **FINE})  # fmt: skip
    expected = _float64_march(
        volume, _label_sample(volume, tf), camera, w, h, 0.37, pixel_phases("random", w, h, 3)
    )
    assert expected[..., 3].max() > 0.5
    np.testing.assert_allclose(image, expected, atol=1e-5)


def test_channels_are_a_float64_ray_casters_samples():
    """As for labels: the samples of a float64 ray caster of the channel model (Max 1995)."""
    volume, tf = channel_scene()
    camera = Camera.orbit(volume.bounds, 35, 25, zoom=1.2)
    w, h = 20, 16
    image, _ = draw(volume, tf, camera, (w, h), step=0.37, options={"depth_offsets": "random", "jitter_seed": 3,
                                                                   "hidden_volume_removal": False, **FINE})  # fmt: skip
    expected = _float64_march(volume, _channel_sample(volume, tf), camera, w, h, 0.37,
                              pixel_phases("random", w, h, 3))  # fmt: skip
    assert expected[..., 3].max() > 0.5
    np.testing.assert_allclose(image, expected, atol=1e-5)


def test_labels_and_channels_against_the_reference():
    """The kit's scenes within objectorder's declared accuracy of the reference renderer (float64,
    refined integration of the same model)."""
    camera_of = lambda volume: Camera.orbit(volume.bounds, 30, 25, zoom=1.2)  # noqa: E731
    for volume, tf in (label_scene(), channel_scene()):
        camera = camera_of(volume)
        image, _ = draw(volume, tf, camera, (32, 32))
        expected = reference_image(volume, tf, camera, 32, 32).astype(np.float64)
        assert expected[..., 3].max() > 0.5
        assert np.sqrt(np.mean((image - expected) ** 2)) < RMSE / 4


@pytest.mark.parametrize("kind", ["labels", "channels"])
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_the_kit_slabs_closed_forms(kind, sign):
    """A slab seen along x: the label's weight ramps over the boundary cell (half a cell more), the
    channels' extinctions add; every pixel against the closed form."""
    volume, tf = label_slab() if kind == "labels" else channel_slab()
    rgba = label_slab_rgba() if kind == "labels" else channel_slab_rgba()
    b = volume.bounds
    image, _ = draw(volume, tf, axis_camera(b, 0, sign, 0.35 * min(b[3] - b[2], b[5] - b[4])), (16, 16))
    np.testing.assert_allclose(image, np.broadcast_to(rgba, image.shape), atol=1e-5)


def test_labels_that_all_draw_alike_give_the_plain_image():
    """Every label in the volume's TF: the plain frame, the same cells visited."""
    volume, tf = label_scene()
    camera = Camera.orbit(volume.bounds, 30, 25, zoom=1.2)
    plain, r_plain = draw(volume, tf.base, camera, options=FINE)
    labelled, r_labels = draw(volume, LabelTransferFunction(tf.base), camera, options=FINE)
    assert plain[..., 3].max() > 0.5
    np.testing.assert_allclose(labelled, plain, atol=2e-6)
    assert r_labels.last_frame.counters["cells_visible"] == r_plain.last_frame.counters["cells_visible"]


def test_one_drawn_channel_gives_the_plain_image():
    """Channels 1 and 2 hidden: channel 0's plain frame (its values and TF)."""
    volume, tf = channel_scene()
    camera = Camera.orbit(volume.bounds, 30, 25, zoom=1.2)
    one = ChannelTransferFunction(tf.tfs, tf.weights, [True, False, False])
    plain, _ = draw(UniformVolume(volume.channels.values[0], spacing=volume.spacing), tf.tfs[0], camera,  # type: ignore[union-attr]
                    options=FINE)  # fmt: skip
    mixed, _ = draw(volume, one, camera, options=FINE)
    assert plain[..., 3].max() > 0.3
    np.testing.assert_allclose(mixed, plain, atol=2e-6)


def test_hidden_labels_give_nothing_and_cost_no_samples():
    """Every label hidden: a clear image, no cell visited, no sample; one label hidden: fewer cells
    and samples (the octree classifies cells by their corners' labels)."""
    volume, tf = label_scene()
    camera = Camera.orbit(volume.bounds, 30, 25, zoom=1.2)
    hidden = LabelTransferFunction(tf.base, default=LabelStyle(visible=False))
    image, r = draw(volume, hidden, camera)
    assert not image.any()
    assert r.last_frame.counters["samples"] == 0 and r.last_frame.counters["cells_visible"] == 0
    shown = LabelTransferFunction(tf.base)
    fewer = LabelTransferFunction(tf.base, {1: LabelStyle(visible=False)})
    _, r_all = draw(volume, shown, camera, options={"hidden_volume_removal": False})
    _, r_fewer = draw(volume, fewer, camera, options={"hidden_volume_removal": False})
    c_all, c_fewer = r_all.last_frame.counters, r_fewer.last_frame.counters
    assert c_fewer["cells_visible"] < 0.8 * c_all["cells_visible"]
    assert c_fewer["samples"] < 0.8 * c_all["samples"]


def test_skipping_changes_no_pixel():
    """Octree skipping and hidden volume removal off: the same label and channel images."""
    off = {"octree_skipping": False, "hidden_volume_removal": False}
    for volume, tf in (label_scene(), channel_scene()):
        camera = Camera.orbit(volume.bounds, 30, 25, zoom=1.2)
        on, _ = draw(volume, tf, camera)
        plain, _ = draw(volume, tf, camera, options=off)
        np.testing.assert_allclose(on, plain, atol=2e-3)  # hidden volume removal stops rays at 0.999


@pytest.mark.parametrize(
    "settings",
    [{"blend_mode": BlendMode.MAXIMUM}, {"shade": True}, {"preintegration": True}],
    ids=["maximum", "shade", "preintegration"],
)
def test_refusals(settings):
    """Labels and channels are drawn composite, post-classified and unshaded: anything else is
    refused in one line."""
    for volume, tf in (label_scene(), channel_scene()):
        with pytest.raises(VolrenError) as err:
            draw(volume, tf, Camera.orbit(volume.bounds, 30, 25), (8, 8), **settings)
        assert "\n" not in str(err.value)
