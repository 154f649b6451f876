"""The `slicer` on label volumes and multi-channel volumes, both paths: against the closed forms of
the kit's slabs, against raycast's `march_labels` / `march_channels` (the same model at the same step, so
only the sample points' float rounding and the tables' resolution differ), and its one-line refusals.

Images are small (40 pixels) because llvmpipe runs every invocation on the CPU.
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.renderers.analytic import rmse
from tests.renderers.raycast_backends import BACKENDS, use_backend
from volren.api import prepared_renderer
from volren.errors import VolrenError
from volren.model import BlendMode, Camera, RenderSettings, TransferFunction1D, UniformVolume
from volren.model.channels import ChannelSet, ChannelTransferFunction
from volren.model.labels import MIXED, LabelMap, LabelStyle, LabelTransferFunction, cell_classes
from volren.testing.channel_scenes import channel_slab, channel_slab_rgba
from volren.testing.label_scenes import label_slab, label_slab_rgba
from volren.testing.scenes import axis_camera

pytestmark = pytest.mark.usefixtures("opengl")

PATHS = ("march", "slices")
SIZE = 40
STEP = 0.5
#: slicer vs raycast at the same step: measured RMSE <= 9e-5 and largest difference <= 1.4e-3 on llvmpipe
#: (float32 sample points and 4096-entry tables against raycast's float64 ones).
RMSE_TOLERANCE = 5e-4
MAX_TOLERANCE = 5e-3
TF = TransferFunction1D(
    [[0.0, 1.0, 1.0, 1.0], [1.0, 1.0, 0.5, 0.2]], [[0.0, 0.0], [0.2, 0.05], [1.0, 0.3]], 2.0
)


def _grid(n: int = 20) -> tuple[np.ndarray, ...]:
    z, y, x = np.mgrid[0:n, 0:n, 0:n].astype(float)
    r = np.sqrt((x - n / 2) ** 2 + (y - n / 2) ** 2 + (z - n / 2) ** 2)
    return x, y, r, np.exp(-((r / (n / 3)) ** 2))


def labelled_blob() -> tuple[UniformVolume, LabelTransferFunction]:
    """A Gaussian blob; a ball of label 3 in its own colour and twice as opaque, a hidden slab of
    label 1 cutting it (label 4 where they meet) and labels 0 and 4 with the volume's TF: hidden,
    recoloured and mixed cells."""
    x, _, r, values = _grid()
    labels = (r < 20 / 3).astype(np.uint8) * 3 + (x < 5)
    volume = UniformVolume(values, spacing=(1.0, 0.9, 1.1), labels=LabelMap(labels))
    styles = {1: LabelStyle(visible=False), 3: LabelStyle(color=(0.1, 0.9, 0.3), opacity=2.0)}
    return volume, LabelTransferFunction(TF, styles)


def channel_field(count: int = 2) -> tuple[UniformVolume, ChannelTransferFunction]:
    """The blob and an offset Gaussian ridge (and, for count > 4, copies of them scaled, one of
    them hidden): overlapping channels with their own ranges, the second at weight 1.5."""
    x, y, _, values = _grid()
    ridge = np.exp(-((x - 6) ** 2 + (y - 8) ** 2) / 20.0) * 3 + 1.0
    fields = [values, ridge] + [(values if c % 2 else ridge) * (1 + 0.3 * c) for c in range(2, count)]
    ridge_tf = TransferFunction1D([[1.0, 0.9, 0.1, 0.8], [4.0, 0.2, 0.2, 1.0]], [[1.0, 0.0], [4.0, 0.6]], 2.0)
    tfs = [TF, ridge_tf]
    for c in range(2, count):
        lo, hi = float(fields[c].min()), float(fields[c].max())
        tfs.append(
            TransferFunction1D(
                [[lo, 0.1 * c, 0.8, 0.3], [hi, 0.9, 0.1 * c, 0.6]], [[lo, 0.0], [hi, 0.3]], 2.0
            )
        )
    stack = np.stack(fields)
    volume = UniformVolume(stack[0], spacing=(1.0, 0.9, 1.1), channels=ChannelSet(stack))
    tf = ChannelTransferFunction(tfs, [1.0, 1.5] + [0.5] * (count - 2))
    if count > 4:
        tf.set_visible(3, False)
    return volume, tf


def _camera(volume: UniformVolume) -> Camera:
    return Camera.orbit(volume.bounds, 30.0, 20.0)


def _render(name: str, volume: UniformVolume, tf, camera: Camera, size: int = SIZE, **settings) -> np.ndarray:
    settings.setdefault("step", STEP)
    with prepared_renderer(name, volume, tf, RenderSettings(**settings)) as renderer:
        return renderer.render(camera, size, size)


@pytest.mark.parametrize("path", PATHS)
def test_label_slab_is_its_closed_form(path: str) -> None:
    """The kit's slab: the label's weight ramps over the boundary cell, adding half a cell."""
    volume, tf = label_slab()
    b = volume.bounds
    camera = axis_camera(b, 0, 1.0, 0.35 * min(b[3] - b[2], b[5] - b[4]))
    image = _render("slicer", volume, tf, camera, 16, options={"path": path})
    np.testing.assert_allclose(image, np.broadcast_to(label_slab_rgba(), image.shape), atol=2e-5)


@pytest.mark.parametrize("path", PATHS)
def test_channel_slab_is_its_closed_form(path: str) -> None:
    """The kit's two-channel slab: one medium of the summed weighted extinctions."""
    volume, tf = channel_slab()
    b = volume.bounds
    camera = axis_camera(b, 0, -1.0, 0.35 * min(b[3] - b[2], b[5] - b[4]))
    image = _render("slicer", volume, tf, camera, 16, options={"path": path})
    np.testing.assert_allclose(image, np.broadcast_to(channel_slab_rgba(), image.shape), atol=2e-5)


@pytest.mark.parametrize("backend", BACKENDS)
def test_labels_match_raycast(backend: str, monkeypatch: pytest.MonkeyPatch) -> None:
    volume, tf = labelled_blob()
    labels = volume.labels
    assert labels is not None
    cells = cell_classes(labels.values, tf.classes(labels.max_label).lookup)[:-1, :-1, :-1]
    assert (cells == MIXED).any() and (cells == -1).any() and (cells >= 0).any()
    camera = _camera(volume)
    use_backend(backend, monkeypatch)
    expected = _render("raycast", volume, tf, camera)
    assert expected[..., 3].max() > 0.5
    for path in PATHS:
        image = _render("slicer", volume, tf, camera, options={"path": path})
        assert rmse(image, expected) < RMSE_TOLERANCE, path
        assert np.abs(image - expected).max() < MAX_TOLERANCE, path
    # the labels matter here: the volume's TF alone is far off
    assert rmse(_render("slicer", volume, TF, camera), expected) > 50 * RMSE_TOLERANCE


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("count", [2, 6])
def test_channels_match_raycast(count: int, backend: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """Two channels (one texture) and six with one hidden (two textures, five drawn)."""
    volume, tf = channel_field(count)
    camera = _camera(volume)
    use_backend(backend, monkeypatch)
    expected = _render("raycast", volume, tf, camera)
    assert expected[..., 3].max() > 0.5
    for path in PATHS:
        image = _render("slicer", volume, tf, camera, options={"path": path})
        assert rmse(image, expected) < RMSE_TOLERANCE, path
        assert np.abs(image - expected).max() < MAX_TOLERANCE, path
    # every channel matters: channel 0 alone is far off
    alone = ChannelTransferFunction(tf.tfs, [1.0] + [0.0] * (count - 1))
    assert rmse(_render("slicer", volume, alone, camera), expected) > 50 * RMSE_TOLERANCE


@pytest.mark.parametrize("path", PATHS)
def test_labels_above_255_draw_as_their_renumbering(path: str) -> None:
    """16-bit labels, and labels in the lookup texture's second row: renaming the labels (and their
    styles) changes nothing."""
    volume, tf = labelled_blob()
    assert volume.labels is not None
    renamed = {0: 0, 1: 1100, 3: 3000}
    labels = np.zeros(volume.labels.values.shape, np.uint16)
    for old, new in renamed.items():
        labels[volume.labels.values == old] = new
    big = UniformVolume(volume.values, spacing=volume.spacing, labels=LabelMap(labels))
    styles = {renamed[label]: style for label, style in tf.styles.items()}
    camera = _camera(volume)
    expected = _render("slicer", volume, tf, camera, options={"path": path})
    image = _render("slicer", big, LabelTransferFunction(TF, styles), camera, options={"path": path})
    assert expected[..., 3].max() > 0.5
    np.testing.assert_array_equal(image, expected)


@pytest.mark.parametrize("path", PATHS)
def test_no_drawn_channel_draws_nothing(path: str) -> None:
    volume, tf = channel_field(2)
    hidden = ChannelTransferFunction(tf.tfs, [0.0, 1.0])
    hidden.set_visible(1, False)
    assert not _render("slicer", volume, hidden, _camera(volume), 16, options={"path": path}).any()


def test_a_new_label_style_is_drawn_on_the_next_frame() -> None:
    """The class tables, cell classes and lookup follow the TF: a renderer that drew one style and
    then gets another draws what a fresh renderer draws."""
    volume, tf = labelled_blob()
    camera = _camera(volume)
    changed = tf.copy()
    changed.set_styles({1: LabelStyle(color=(0.9, 0.1, 0.9)), 0: LabelStyle(visible=False)})
    with prepared_renderer("slicer", volume, tf, RenderSettings(step=STEP)) as renderer:
        first = renderer.render(camera, SIZE, SIZE)
        renderer.set_transfer_function(changed)
        second = renderer.render(camera, SIZE, SIZE)
    fresh = _render("slicer", volume, changed, camera)
    assert rmse(first, fresh) > 0.01
    np.testing.assert_array_equal(second, fresh)


@pytest.mark.parametrize("scene", [labelled_blob, channel_field])
@pytest.mark.parametrize(
    ("settings", "words"),
    [
        ({"blend_mode": BlendMode.MAXIMUM}, "composite only"),
        ({"shade": True}, "unshaded"),
        ({"preintegration": True}, "pre-integration"),
    ],
)
def test_what_is_not_drawn_is_refused_in_one_line(scene, settings: dict, words: str) -> None:
    volume, tf = scene()
    with pytest.raises(VolrenError) as error:
        _render("slicer", volume, tf, _camera(volume), 8, **settings)
    assert words in str(error.value) and "\n" not in str(error.value)
