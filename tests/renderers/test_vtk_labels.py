"""`vtk` on label volumes (the GPU ray caster's label-map mask: `volren.renderers.vtk_mappers.labels`)
against closed forms, the plain volume and `reference`.

Why these bounds (measured with VTK 9.7.2 on Mesa llvmpipe, 8-bit framebuffer, step 0.5): VTK takes
one label per sample, so a label boundary falls at a cell's middle or its end, not where the
model's trilinear label weights put it (Real-Time Volume Graphics 16.5: half a cell of partial
weight); the kit's slab comes out as one of those two closed forms. On the three-label scene that
is RMSE 0.030 to `reference` at step 0.5 and 0.016 at 0.25 (VTK's label TFs read uncorrected:
0.093 and 0.146, growing as the step shrinks).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.clip_region import ClipPlane, ClipRegion
from volren.model.labels import LabelMap, LabelStyle, LabelTransferFunction
from volren.model.settings import BlendMode, RenderSettings
from volren.model.volume import UniformVolume
from volren.renderers.vtk_mappers.renderer import VtkRenderer
from volren.testing import label_scenes
from volren.testing.label_scenes import label_scene, label_slab
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


def labels_of(volume: UniformVolume) -> np.ndarray:
    assert volume.labels is not None
    return volume.labels.values


def scene_camera(volume: UniformVolume) -> Camera:
    return Camera.orbit(volume.bounds, 30, 25, zoom=1.2)


def slab_alpha(cells: float) -> float:
    """The slab's alpha through `cells` cells of its label (`label_scenes.label_slab_rgba`)."""
    tau = -math.log1p(-label_scenes.SLAB_OPACITY) / label_scenes.SLAB_UNIT
    return -math.expm1(-tau * label_scenes.SLAB_SPACING[0] * cells)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_the_slab_boundary_falls_at_a_cell_middle_or_end(sign: float) -> None:
    """The labelled cell after the boundary cell, plus half (the model, and VTK's nearest label
    from one side) or all (VTK from the other side) of the boundary cell; in the label's colour."""
    volume, tf = label_slab()
    b = volume.bounds
    image = draw(volume, tf, axis_camera(b, 0, sign, 0.35 * min(b[3] - b[2], b[5] - b[4])), 16)
    whole = label_scenes.SLAB_DIMS[0] - 1 - label_scenes.SLAB_FIRST
    alpha = image[..., 3]
    candidates = [slab_alpha(whole + 0.5), slab_alpha(whole + 1.0)]  # 0.840, 0.913
    assert min(abs(float(alpha.mean()) - a) for a in candidates) <= 2 * LSB
    assert np.ptp(alpha) <= LSB
    rgb = np.asarray(label_scenes.SLAB_COLOUR) * float(alpha.mean())
    assert np.abs(image[..., :3] - rgb).max() <= 2 * LSB


@pytest.mark.parametrize(("step", "bound", "silhouette"), [(0.5, 0.04, 0.03), (0.25, 0.022, 0.015)])
def test_three_labels_against_reference(step: float, bound: float, silhouette: float) -> None:
    """The kit's three labels (one hidden, one in its own colour at twice the opacity): the error
    shrinks with the step, which it would not if the label TFs' opacity went uncorrected. The
    silhouette (alpha above 0.05 or not) differs from the reference's in 2.0 % of the pixels at
    step 0.5 and 0.9 % at 0.25 (measured)."""
    volume, tf = label_scene()
    camera = scene_camera(volume)
    reference = reference_image(volume, tf, camera, SIZE, SIZE)
    image = draw(volume, tf, camera, step=step)
    assert rmse(image, reference) <= bound
    covered = (image[..., 3] > 0.05) != (reference[..., 3] > 0.05)
    assert covered.mean() <= silhouette


@pytest.mark.parametrize("label", [0, 7])
def test_one_label_draws_the_plain_volume(label: int) -> None:
    """A volume of one label drawing with the base TF is the plain volume: label 0 through VTK's
    own TF, another label through a label TF holding the per-sample opacity."""
    volume, tf = label_scene()
    labels = LabelMap(np.full(volume.values.shape, label, np.uint8))
    one = UniformVolume(volume.values, spacing=volume.spacing, labels=labels)
    camera = scene_camera(volume)
    image = draw(one, LabelTransferFunction(tf.base), camera)
    plain = draw(UniformVolume(volume.values, spacing=volume.spacing), tf.base, camera)
    assert image[..., 3].max() > 0.5
    assert np.abs(image - plain).max() <= 2 * LSB


def test_a_hidden_label_and_a_recoloured_one() -> None:
    """Hiding the only label draws nothing; giving it a colour draws the plain volume's alpha in it."""
    volume, tf = label_scene()
    labels = LabelMap(np.full(volume.values.shape, 4, np.uint8))
    one = UniformVolume(volume.values, spacing=volume.spacing, labels=labels)
    camera = scene_camera(volume)
    assert not draw(one, LabelTransferFunction(tf.base, {4: LabelStyle(visible=False)}), camera).any()
    red = draw(one, LabelTransferFunction(tf.base, {4: LabelStyle(color=(1.0, 0.0, 0.0))}), camera)
    plain = draw(UniformVolume(volume.values, spacing=volume.spacing), tf.base, camera)
    assert np.abs(red[..., 3] - plain[..., 3]).max() <= 2 * LSB
    assert np.abs(red[..., 0] - red[..., 3]).max() <= LSB and not red[..., 1:3].any()


def test_clipped_labels_against_reference() -> None:
    """The GPU mapper's clipping planes cut label volumes too (measured RMSE 0.042)."""
    volume, tf = label_scene()
    camera = scene_camera(volume)
    clip = ClipRegion(planes=(ClipPlane((5.0, 5.0, 5.0), (1.0, 0.3, 0.2)),))
    reference = reference_image(volume, tf, camera, SIZE, SIZE, RenderSettings(clip=clip))
    whole = reference_image(volume, tf, camera, SIZE, SIZE)
    image = draw(volume, tf, camera, clip=clip)
    assert rmse(image, reference) <= 0.05
    assert rmse(image, whole) > 0.15


def wide_labels() -> tuple[UniformVolume, LabelTransferFunction]:
    volume, tf = label_scene()
    values = labels_of(volume).astype(np.uint16)
    values[0, 0, 0] = 300
    return UniformVolume(volume.values, spacing=volume.spacing, labels=LabelMap(values)), tf


@pytest.mark.parametrize(
    ("scene", "settings", "words"),
    [
        (label_scene, {"options": {"mapper": "fixed_point"}}, "GPU ray cast mapper"),
        (label_scene, {"options": {"mapper": "smart"}}, "GPU ray cast mapper"),
        (label_scene, {"blend_mode": BlendMode.MINIMUM}, "composite only"),
        (label_scene, {"shade": True}, "unshaded only"),
        (wide_labels, {}, "labels up to 255 only .* up to 300"),
    ],
)
def test_what_vtk_cannot_draw_is_refused_in_one_line(scene, settings: dict, words: str) -> None:
    volume, tf = scene()
    calls: list[float] = []
    with VtkRenderer() as renderer:
        renderer.set_volume(volume)
        renderer.set_settings(RenderSettings(**settings))
        renderer.set_transfer_function(tf)
        with pytest.raises(VolrenError, match=words) as info:
            renderer.render(scene_camera(volume), 8, 8, calls.append)
    assert "\n" not in str(info.value) and not calls


def test_the_plain_volume_draws_again_after_labels() -> None:
    """One renderer switching from labels back to the volume's own TF draws what a fresh one does
    (VTK's label TFs and mask are taken off)."""
    volume, tf = label_scene()
    camera = scene_camera(volume)
    with VtkRenderer() as renderer:
        renderer.set_volume(volume)
        renderer.set_transfer_function(tf)
        labelled = renderer.render(camera, SIZE, SIZE)
        renderer.set_transfer_function(tf.base)
        again = renderer.render(camera, SIZE, SIZE)
    plain = draw(volume, tf.base, camera)
    assert np.array_equal(again, plain)
    assert np.abs(labelled - plain).max() > 0.2


def test_labels_over_nan_values() -> None:
    """Half the field NaN: transparent there whatever the label (measured RMSE 0.027)."""
    volume, tf = label_scene()
    values = volume.values.copy()
    values[:, :, 6:] = np.nan
    holed = UniformVolume(values, spacing=volume.spacing, labels=volume.labels)
    camera = scene_camera(volume)
    reference = reference_image(holed, tf, camera, SIZE, SIZE)
    assert rmse(draw(holed, tf, camera), reference) <= 0.04
