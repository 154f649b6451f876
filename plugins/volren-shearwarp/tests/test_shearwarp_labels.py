"""Label and multi-channel volumes in shear-warp (`mixed_composite`): against the float64 reference,
against the plain path where the labels or channels reduce to one TF, hidden labels, the runs
changing no pixel, and the refusals (pre-integration, other blend modes, shading)."""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest
from volren_shearwarp import ShearWarpRenderer
from volren_shearwarp.mixed_frame import hidden_points

from volren.errors import VolrenError
from volren.model import BlendMode, Camera, RenderSettings, TransferFunction1D, UniformVolume
from volren.model.channels import ChannelSet, ChannelTransferFunction
from volren.model.clip_region import ClipPlane, ClipRegion
from volren.model.labels import LabelMap, LabelStyle, LabelTransferFunction, cell_classes
from volren.testing import image_error
from volren.testing.channel_scenes import channel_scene
from volren.testing.label_scenes import label_scene
from volren.testing.reference_images import reference_image
from volren.testing.render_helpers import render_checked

draw = partial(render_checked, ShearWarpRenderer)
ACCURACY = ShearWarpRenderer.capabilities.kinds["uniform"].accuracy.rmse
#: The plain path's bilinear LUT is float32 and its fast spans compute in float32; the label and
#: channel tables are float64: images agree to float32 rounding over a few dozen segments.
FLOAT32_SUM = 2e-5


def _striped(shape: tuple[int, int, int]) -> LabelMap:
    """Labels 0..3 in stripes and a ball: boundaries in every direction."""
    k, j, i = np.indices(shape)
    labels = ((i + 2 * j) // 3 % 3).astype(np.uint8)
    labels[(i - shape[2] / 2) ** 2 + (j - shape[1] / 2) ** 2 + (k - shape[0] / 2) ** 2 < 9] = 3
    return LabelMap(labels)


def _smooth_volume(labels: bool = True, channels: ChannelSet | None = None) -> UniformVolume:
    shape = (10, 11, 12)
    k, j, i = np.indices(shape).astype(np.float64)
    values = np.sin(0.9 * i) + np.cos(1.3 * j) + 0.5 * k * 1.1
    return UniformVolume(values, spacing=(0.9, 1.0, 1.1), name="smooth",
                         labels=_striped(shape) if labels else None, channels=channels)  # fmt: skip


BASE = TransferFunction1D([[-2, 0.2, 0.3, 1.0], [4, 1.0, 0.8, 0.1]], [[-1, 0.0], [4, 0.5]], 1.0)


@pytest.mark.parametrize("parallel", [False, True])
@pytest.mark.parametrize("step", [0.25, 0.5, 1.0])
def test_three_labels_match_the_reference_within_the_declared_accuracy(parallel, step):
    """The kit's label scene (a hidden label, one in its own colour at twice the opacity) in both
    projections, with sub-planes (step 0.25), every slice, and every other slice (step 1)."""
    volume, tf = label_scene()
    camera = Camera.orbit(volume.bounds, 30, 25, zoom=1.2, parallel=parallel)
    image, _ = draw(volume, tf, camera, (40, 32), step=step)
    reference = reference_image(volume, tf, camera, 40, 32, RenderSettings(step=step))
    assert reference[..., 3].max() > 0.5
    assert image_error(image, reference).rmse <= ACCURACY


@pytest.mark.parametrize("kind", ["labels", "channels"])
def test_a_clip_plane_cuts_labels_and_channels_as_the_reference_does(kind):
    """An oblique plane through the middle (`RenderSettings.clip`): each ray narrowed to the kept side,
    a cut segment sampled at the cut, as the plain path does."""
    volume, tf = label_scene() if kind == "labels" else channel_scene()
    b = volume.bounds
    centre = ((b[0] + b[1]) / 2, (b[2] + b[3]) / 2, (b[4] + b[5]) / 2)
    settings = RenderSettings(clip=ClipRegion((ClipPlane(centre, (1.0, 0.4, -0.3)),)))
    camera = Camera.orbit(volume.bounds, 30, 25, zoom=1.2)
    image, renderer = draw(volume, tf, camera, (40, 32), clip=settings.clip)
    reference = reference_image(volume, tf, camera, 40, 32, settings)
    assert renderer.last_frame.counters["clipped"] == 1.0
    assert reference[..., 3].max() > 0.3
    assert image_error(image, reference).rmse <= ACCURACY


@pytest.mark.parametrize("parallel", [False, True])
def test_three_channels_match_the_reference_within_the_declared_accuracy(parallel):
    volume, tf = channel_scene()
    camera = Camera.orbit(volume.bounds, -50, 35, zoom=1.2, parallel=parallel)
    image, _ = draw(volume, tf, camera, (40, 32))
    reference = reference_image(volume, tf, camera, 40, 32)
    assert reference[..., 3].max() > 0.5
    assert image_error(image, reference).rmse <= ACCURACY


@pytest.mark.parametrize("azimuth, elevation", [(30, 25), (100, -40), (0, 90)])
def test_labels_that_all_draw_alike_give_the_plain_image(azimuth, elevation):
    """Every label in the volume's TF: one class, every cell on the fast path, and the segment's two
    halves classified as the plain post-classified path does with bilinear lookups."""
    volume = _smooth_volume()
    camera = Camera.orbit(volume.bounds, azimuth, elevation, zoom=1.2, parallel=True)
    options = {"lookup": "bilinear", "table_size": 256}
    plain, _ = draw(volume, BASE, camera, options=options)
    labelled, renderer = draw(volume, LabelTransferFunction(BASE), camera, options=options)
    assert plain[..., 3].max() > 0.5
    assert np.abs(labelled - plain).max() <= FLOAT32_SUM
    assert renderer.last_frame.counters["samples"] > 0


def test_one_channel_gives_the_plain_image_and_its_weight_scales_the_extinction():
    """One channel (the volume's values) in a TF of constant opacity, where interpolating the table's
    depths (channels) and its opacities (plain) agree: the plain image; at weight 2 the plain image of
    the TF with half the unit distance (tau doubles)."""
    volume = _smooth_volume(labels=False)
    values = np.asarray(volume.values)[None]
    volume = _smooth_volume(labels=False, channels=ChannelSet(values))
    tf = TransferFunction1D([[-2, 0.2, 0.3, 1.0], [4, 1.0, 0.8, 0.1]], [[-2, 0.3], [4, 0.3]], 1.0)
    half = TransferFunction1D([[-2, 0.2, 0.3, 1.0], [4, 1.0, 0.8, 0.1]], [[-2, 0.3], [4, 0.3]], 0.5)
    camera = Camera.orbit(volume.bounds, 40, 20, zoom=1.2, parallel=True)
    options = {"lookup": "bilinear", "table_size": 256}
    for weight, plain_tf in ((1.0, tf), (2.0, half)):
        plain, _ = draw(volume, plain_tf, camera, options=options)
        mixed, _ = draw(volume, ChannelTransferFunction([tf], [weight]), camera, options=options)
        assert plain[..., 3].max() > 0.5
        assert np.abs(mixed - plain).max() <= FLOAT32_SUM


def test_hidden_labels_draw_nothing_and_cost_nothing():
    """All labels hidden: a black frame without a segment. A hidden label filling the volume but for a
    small block of a shown one, under a TF that makes every value visible (runs over the values alone
    skip nothing): the hidden cells are skipped like empty space, so the frame composites well under
    half the segments of the same frame without runs, and the same image (early termination off)."""
    volume = _smooth_volume()
    camera = Camera.orbit(volume.bounds, 30, 25, zoom=1.2)
    hidden = LabelTransferFunction(BASE, default=LabelStyle(visible=False))
    image, renderer = draw(volume, hidden, camera)
    assert not image.any()
    assert renderer.last_frame.counters["samples"] == 0
    labels = np.ones(volume.values.shape, np.uint8)
    labels[2:5, 2:5, 2:5] = 2
    volume = UniformVolume(volume.values, spacing=volume.spacing, labels=LabelMap(labels))
    block = LabelTransferFunction(BASE, {1: LabelStyle(visible=False)})
    skipped, renderer = draw(volume, block, camera, options={"early_termination": False})
    walked, walker = draw(
        volume, block, camera, options={"early_termination": False, "empty_space_skipping": False}
    )
    assert skipped[..., 3].max() > 0.05
    np.testing.assert_array_equal(skipped, walked)
    assert renderer.last_frame.counters["samples"] < 0.4 * walker.last_frame.counters["samples"]


def test_hidden_points_are_those_whose_cells_are_all_hidden():
    """A point is masked out of the runs exactly when every cell it is a corner of has all eight
    corners hidden (brute force over the cells)."""
    rng = np.random.default_rng(3)
    labels = (rng.random((6, 7, 8)) < 0.8).astype(np.uint8)  # label 1 (hidden) mostly, 0 shown
    cells = cell_classes(labels, np.array([0, -1], np.int32))
    got = hidden_points(cells)
    nz, ny, nx = labels.shape
    for k, j, i in np.ndindex(labels.shape):
        around = [labels[c : c + 2, b : b + 2, a : a + 2]
                  for c in (k - 1, k) for b in (j - 1, j) for a in (i - 1, i)
                  if 0 <= c < nz - 1 and 0 <= b < ny - 1 and 0 <= a < nx - 1]  # fmt: skip
        assert got[k, j, i] == all((cell == 1).all() for cell in around)


@pytest.mark.parametrize("kind", ["labels", "channels"])
@pytest.mark.parametrize("parallel, step", [(True, 0.5), (False, 0.5), (False, 1.0), (True, 0.25)])
def test_empty_space_skipping_changes_no_pixel(kind, parallel, step):
    """The runs (over the classes' or channels' supports, hidden labels masked) skip only segments
    that add nothing: the image equals the one without them, bit for bit."""
    sparse = TransferFunction1D([[-2, 0.2, 0.3, 1.0], [6, 1.0, 0.8, 0.1]], [[3.0, 0.0], [6, 0.6]], 1.0)
    if kind == "labels":
        volume = _smooth_volume()
        tf: LabelTransferFunction | ChannelTransferFunction = LabelTransferFunction(
            sparse, {2: LabelStyle(visible=False), 3: LabelStyle(color=(1, 0, 0), opacity=3.0)}
        )
    else:
        values = np.asarray(_smooth_volume().values)
        k, j, i = np.indices(values.shape)
        blob = np.exp(-((i - 3.0) ** 2 + (j - 7.0) ** 2 + (k - 5.0) ** 2) / 4.0)
        volume = _smooth_volume(labels=False, channels=ChannelSet(np.stack([values, blob])))
        spot = TransferFunction1D([[0, 1.0, 0.0, 1.0], [1, 1.0, 0.5, 1.0]], [[0.3, 0.0], [1.0, 0.9]], 1.0)
        tf = ChannelTransferFunction([sparse, spot], [1.0, 2.0])
    camera = Camera.orbit(volume.bounds, 35, 20, zoom=1.2, parallel=parallel)
    skipped, renderer = draw(volume, tf, camera, step=step)
    walked, _ = draw(volume, tf, camera, step=step, options={"empty_space_skipping": False})
    assert renderer.last_frame.counters["empty_pixels_skipped"] > 0
    assert skipped[..., 3].max() > 0.1
    np.testing.assert_array_equal(skipped, walked)


@pytest.mark.parametrize(
    "settings, words",
    [
        ({"preintegration": True}, "pre-integration"),
        ({"blend_mode": BlendMode.MAXIMUM}, "composite only"),
        ({"shade": True}, "shading"),
        ({"jitter": True}, "jitter"),
    ],
)
@pytest.mark.parametrize("kind", ["labels", "channels"])
def test_what_labels_and_channels_do_not_draw_is_refused_in_one_line(kind, settings, words):
    volume, tf = label_scene() if kind == "labels" else channel_scene()
    renderer = ShearWarpRenderer()
    renderer.set_volume(volume)
    renderer.set_transfer_function(tf)
    renderer.set_settings(RenderSettings(**settings))
    calls: list[float] = []
    with pytest.raises(VolrenError) as err:
        renderer.render(Camera.orbit(volume.bounds, 30, 25), 16, 16, progress=calls.append)
    assert words in str(err.value) and "\n" not in str(err.value)
    assert not calls
