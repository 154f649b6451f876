"""The conformance kit's `channels` check: it passes the reference, fails a renderer that draws a
channel TF's first channel alone (claiming channels or not), and passes over renderers that refuse
channels as they declare. The slab's closed form is checked against the channel model's own float64
oracle, and the channels are part of the key of the cached reference images."""

from __future__ import annotations

import hashlib
import json
from dataclasses import replace

import numpy as np

from volren.model.channels import ChannelSet, ChannelTransferFunction
from volren.model.volume import UniformVolume
from volren.renderers.base import Capabilities
from volren.renderers.reference import ReferenceRenderer
from volren.testing import CHECKS, run_check
from volren.testing.channel_scenes import (
    SLAB_DIMS,
    SLAB_SPACING,
    channel_scene,
    channel_slab,
    channel_slab_rgba,
)
from volren.testing.reference_images import volume_digest

CHANNELS = next(c for c in CHECKS if c.name == "channels")


def with_uniform(**changes) -> Capabilities:
    """The reference's capabilities with these changes to its uniform grids' support."""
    caps = ReferenceRenderer.capabilities
    return replace(caps, kinds={**caps.kinds, "uniform": replace(caps.kinds["uniform"], **changes)})  # type: ignore[index]


class IgnoresChannels(ReferenceRenderer):
    """Claims channels, but draws the volume's own values with the first channel's TF."""

    def set_transfer_function(self, tf):
        super().set_transfer_function(tf.tfs[0] if isinstance(tf, ChannelTransferFunction) else tf)


class DrawsUndeclaredChannels(IgnoresChannels):
    """Does not claim channels, yet draws a frame when given a channel TF."""

    capabilities = with_uniform(channels=False)


class RefusesChannels(ReferenceRenderer):
    capabilities = with_uniform(channels=False)


class Preintegrates(ReferenceRenderer):
    """Claims pre-integration (the reference ignores it): channels pre-integrated must be refused."""

    capabilities = with_uniform(preintegration=True)


def lines(renderer: type) -> list[str]:
    result = run_check(CHANNELS, renderer, quick=True)
    print("\n".join(result.lines()))
    assert result.error is None
    return result.lines()


def test_the_reference_passes_the_channels_check():
    out = lines(ReferenceRenderer)
    assert out and all(line.startswith("PASS channels [") for line in out)
    assert any("[two-channel slab, from +x]" in line for line in out)
    assert any("[three channels] RMSE to reference" in line for line in out)


def test_a_renderer_drawing_one_channel_alone_fails_the_slab_and_the_scene():
    failed = [line for line in lines(IgnoresChannels) if line.startswith("FAIL")]
    assert any("[two-channel slab, from +x] RMSE" in line for line in failed)
    assert any("[three channels] RMSE to reference" in line for line in failed)


def test_a_renderer_not_claiming_channels_must_refuse_them():
    assert lines(RefusesChannels) == [
        "PASS channels [uniform, declared not drawn] refusals not in one line 0 (bound <= 0)"
    ]
    assert lines(DrawsUndeclaredChannels) == [
        "FAIL channels [uniform, declared not drawn] frames drawn instead of refused 1 (bound <= 0)"
    ]


def test_channels_pre_integrated_are_refused():
    assert (
        "PASS channels [pre-integrated, declared not drawn] refusals not in one line 0 (bound <= 0)"
        in lines(Preintegrates)
    )


def test_the_slab_closed_form_is_the_channel_models_integral():
    """Along x through the slab every point has the channels' constant values: integrate the model
    (`ChannelTransferFunction.extinction_emission`) at fine midpoints."""
    volume, tf = channel_slab()
    samples = 100_000
    s = [np.full(samples, volume.channels.values[c, 2, 3, 1]) for c in range(2)]
    tau, q = tf.extinction_emission(s)
    od = tau * SLAB_SPACING[0] * (SLAB_DIMS[0] - 1) / samples
    alpha = -np.expm1(-od)
    trans = np.exp(-np.concatenate([[0.0], np.cumsum(od)[:-1]]))
    rgb = ((trans * alpha)[:, None] * q / tau[:, None]).sum(axis=0)
    assert np.abs(np.append(rgb, 1.0 - np.exp(-od.sum())) - channel_slab_rgba()).max() < 1e-9
    # one channel alone, or the weights ignored, is far from it
    for other in (ChannelTransferFunction(tf.tfs[:1]), ChannelTransferFunction(tf.tfs)):
        t1, _ = other.extinction_emission(s[: other.count])
        assert abs(-np.expm1(-t1[0] * SLAB_SPACING[0] * (SLAB_DIMS[0] - 1)) - channel_slab_rgba()[3]) > 0.01


def test_the_three_channel_scene_overlaps():
    volume, tf = channel_scene()
    values = volume.channels.values
    tau, _ = tf.extinction_emission(list(values))
    shares = [ChannelTransferFunction([tf.tfs[c]], [tf.weights[c]]).extinction_emission([values[c]])[0] / tau.clip(1e-300)
              for c in range(3)]  # fmt: skip
    for share in shares:  # each channel dominates somewhere and they mix elsewhere
        assert share.max() > 0.6 and ((share > 0.2) & (share < 0.8)).sum() > 20


def test_the_channels_key_the_cached_reference_images():
    volume, _ = channel_slab()
    plain = UniformVolume(volume.values, spacing=volume.spacing, origin=volume.origin)
    other = UniformVolume(volume.values, spacing=volume.spacing, origin=volume.origin,
                          channels=ChannelSet(volume.channels.values[::-1].copy()))  # fmt: skip
    digests = {volume_digest(v) for v in (volume, plain, other)}
    assert len(digests) == 3
    # a volume without channels keeps the key it had before channels existed
    h = hashlib.sha256()
    h.update(json.dumps([plain.spacing, plain.origin, plain.values.shape, str(plain.values.dtype)]).encode())
    h.update(np.ascontiguousarray(plain.values).tobytes())
    assert volume_digest(plain) == h.hexdigest()
