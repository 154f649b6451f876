"""The conformance kit's `labels` check: it passes the reference, fails a renderer that draws a
label TF's base TF alone (claiming labels or not), and passes over renderers that refuse labels as
they declare. The slab's closed form is checked against the label model's own float64 oracle, and
a label map is part of the key of the cached reference images."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from volren.model.labels import LabelMap, LabelTransferFunction, cell_label_weights
from volren.model.volume import UniformVolume
from volren.renderers.base import Capabilities
from volren.renderers.reference import ReferenceRenderer
from volren.testing import CHECKS, run_check
from volren.testing.label_scenes import SLAB_DIMS, SLAB_FIRST, label_scene, label_slab, label_slab_rgba
from volren.testing.reference_images import volume_digest

LABELS = next(c for c in CHECKS if c.name == "labels")


def with_uniform(**changes) -> Capabilities:
    """The reference's capabilities with these changes to its uniform grids' support."""
    caps = ReferenceRenderer.capabilities
    return replace(caps, kinds={**caps.kinds, "uniform": replace(caps.kinds["uniform"], **changes)})  # type: ignore[index]


class IgnoresLabels(ReferenceRenderer):
    """Claims labels, but draws a label TF's base TF over the whole volume."""

    def set_transfer_function(self, tf):
        super().set_transfer_function(tf.base if isinstance(tf, LabelTransferFunction) else tf)


class DrawsUndeclaredLabels(IgnoresLabels):
    """Does not claim labels, yet draws a frame when given a label TF."""

    capabilities = with_uniform(labels=False)


class RefusesLabels(ReferenceRenderer):
    capabilities = with_uniform(labels=False)


class PreintegratesPlainOnly(ReferenceRenderer):
    """Claims pre-integration (the reference ignores it), but not with labels."""

    capabilities = with_uniform(preintegration=True)


class PreintegratesLabels(ReferenceRenderer):
    capabilities = with_uniform(preintegration=True, labels_preintegration=True)


def lines(renderer: type) -> list[str]:
    result = run_check(LABELS, renderer, quick=True)
    print("\n".join(result.lines()))
    assert result.error is None
    return result.lines()


def test_the_reference_passes_the_labels_check():
    out = lines(ReferenceRenderer)
    assert out and all(line.startswith("PASS labels [") for line in out)
    assert any("[slab, from +x]" in line for line in out) and any("[three labels" in line for line in out)


def test_a_renderer_drawing_the_base_tf_alone_fails_the_slab_and_the_scene():
    failed = [line for line in lines(IgnoresLabels) if line.startswith("FAIL")]
    assert any("[slab, from +x] RMSE" in line for line in failed)
    assert any("[three labels, pre-integration False] RMSE to reference" in line for line in failed)


def test_a_renderer_not_claiming_labels_must_refuse_them():
    assert lines(RefusesLabels) == [
        "PASS labels [uniform, declared not drawn] refusals not in one line 0 (bound <= 0)"
    ]
    assert lines(DrawsUndeclaredLabels) == [
        "FAIL labels [uniform, declared not drawn] frames drawn instead of refused 1 (bound <= 0)"
    ]


def test_pre_integration_with_labels_is_drawn_or_refused_as_declared():
    plain_only = lines(PreintegratesPlainOnly)
    assert (
        "PASS labels [pre-integrated, declared not drawn] refusals not in one line 0 (bound <= 0)"
        in plain_only
    )
    assert not any("pre-integration True" in line for line in plain_only)
    both = lines(PreintegratesLabels)
    assert any(line.startswith("PASS labels [three labels, pre-integration True]") for line in both)
    assert not any("declared not drawn" in line for line in both)


def test_the_slab_closed_form_is_the_label_models_integral():
    """Along x through the slab the weight of label 1 is 0, then fx over the boundary cell, then 1:
    integrate the model (`LabelTransferFunction.extinction_emission`) at fine midpoints."""
    volume, tf = label_slab()
    nx = SLAB_DIMS[0]
    samples = 200_000
    u = (np.arange(samples) + 0.5) / samples * (nx - 1)  # grid coordinate along x
    cell = np.minimum(np.floor(u).astype(int), nx - 2)
    fx = u - cell
    labels = volume.labels.values[2, 3]  # one row of points along x, inside the slab
    corners = np.stack([labels[cell + (n & 1)] for n in range(8)], axis=-1)
    zero = np.zeros(samples)
    tau, q = tf.extinction_emission(np.full(samples, 0.5), cell_label_weights(corners, fx, zero, zero))
    dl = volume.spacing[0] * (nx - 1) / samples
    od = tau * dl
    alpha = -np.expm1(-od)
    trans = np.exp(-np.concatenate([[0.0], np.cumsum(od)[:-1]]))
    rgb = ((trans * alpha)[:, None] * q / tau[:, None].clip(1e-300)).sum(axis=0)
    expected = label_slab_rgba()
    assert np.abs(np.append(rgb, 1.0 - np.exp(-od.sum())) - expected).max() < 1e-9
    assert np.all(tau[u < SLAB_FIRST - 1] == 0.0)


def test_the_three_label_scene_shows_each_label():
    volume, tf = label_scene()
    present = volume.labels.present
    assert present == (1, 2, 3)
    classes = tf.classes(max(present))
    assert classes.lookup[3] == -1 and classes.lookup[1] != classes.lookup[2]


def test_a_label_map_keys_the_cached_reference_images():
    volume, _ = label_slab()
    plain = UniformVolume(volume.values, spacing=volume.spacing, origin=volume.origin)
    other = UniformVolume(volume.values, spacing=volume.spacing, origin=volume.origin,
                          labels=LabelMap(1 - volume.labels.values))  # fmt: skip
    digests = {volume_digest(v) for v in (volume, plain, other)}
    assert len(digests) == 3
    assert volume_digest(plain) == volume_digest(UniformVolume(volume.values, spacing=volume.spacing,
                                                               origin=volume.origin))  # fmt: skip
