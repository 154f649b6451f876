"""`volren.render` and `volren.drawing` with a multi-channel volume: `channels` (all or a pick),
`channel_tfs`, `channel_weights` and `hidden_channels`, a `UniformVolume` with channels and a
`ChannelTransferFunction` as `tf`; `auto` among renderers that mix channels, pre-integration off;
one-line errors naming the argument. Images only where a renderer already mixes channels."""

from __future__ import annotations

import json

import numpy as np
import pytest
import pyvista as pv

import volren
from volren.errors import VolrenError
from volren.io import save_transfer_function
from volren.io.channel_io import PickedChannels
from volren.model.channels import ChannelTransferFunction
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TransferFunction2D
from volren.model.volume import UniformVolume
from volren.renderers.registry import registry

SHAPE = (6, 5, 4)  # z, y, x
RED = TransferFunction1D([[0, 1, 0, 0]], [[0, 0], [59, 0.7]], 2.0)


def reference_mixes_channels() -> bool:
    return bool(registry.capabilities("reference").kinds["uniform"].channels)


def field() -> np.ndarray:
    z, y, x = np.mgrid[0 : SHAPE[0], 0 : SHAPE[1], 0 : SHAPE[2]]
    return (x + 3 * y + 5 * z).astype(np.float32) / 2


@pytest.fixture
def rgb(tmp_path):
    """rgb.vti: an array of 3 components, component c = field + 10 c; red.json, a 1D TF."""
    img = pv.ImageData(dimensions=SHAPE[::-1])
    img.point_data["rgb"] = np.stack([field().ravel() + 10 * c for c in range(3)], axis=1)
    img.save(tmp_path / "rgb.vti")
    save_transfer_function(RED, tmp_path / "red.json")
    return tmp_path


def test_the_channel_arguments_make_the_scene(rgb):
    d = volren.drawing(rgb / "rgb.vti", channels=[2, 0], channel_tfs={2: rgb / "red.json"},
                       channel_weights={0: 2.0}, hidden_channels=(0,), size=16)  # fmt: skip
    volume, tf = d.scene.volume, d.scene.transfer_function
    assert volume.channels.indices == (2, 0) and np.array_equal(volume.values, field() + 20)
    assert isinstance(tf, ChannelTransferFunction)
    assert tf.tfs[0].to_dict() == RED.to_dict() and tf.weights == [1.0, 2.0] and tf.visible == [True, False]
    assert registry.capabilities(d.scene.renderer).kinds["uniform"].channels
    assert d.scene.settings.preintegration is False


def test_a_volume_with_channels_and_a_channel_tf_as_tf(rgb):
    stacked = np.stack([field(), field() * 2])
    volume = UniformVolume(stacked[0], channels=PickedChannels(stacked))
    given = ChannelTransferFunction([RED, RED], weights=[0.5, 1.0])
    d = volren.drawing(volume, given, size=8)
    assert d.scene.transfer_function.to_dict() == given.to_dict() and d.scene.volume is volume
    # a pick among a volume's own channels, by their numbers; a TF file of kind channels by path
    (rgb / "ctf.json").write_text(json.dumps(ChannelTransferFunction([RED]).to_dict()))
    picked = volren.drawing(volume, rgb / "ctf.json", channels=[1], size=8).scene.volume
    assert np.array_equal(picked.values, field() * 2) and picked.channels.indices == (1,)
    # a 1D TF for every channel; None for the channels' default look
    every = volren.drawing(volume, RED, size=8).scene.transfer_function
    assert [t.to_dict() for t in every.tfs] == [RED.to_dict()] * 2
    default = volren.drawing(rgb / "rgb.vti", channels=True, size=8).scene.transfer_function
    assert default.count == 3 and default.tfs[2].value_range == (10 * 2, field().max() + 20)


@pytest.mark.parametrize(
    "kwargs, problem",
    [
        ({"hidden_channels": (1,)}, r"^hidden_channels: needs a multi-channel volume; rgb.vti is one field"),
        ({"channels": [0], "channel_tfs": {2: RED}}, r"^channel_tfs: channel 2 is not drawn \(the channels drawn: 0\)"),
        ({"channels": True, "channel_weights": {1: -1}}, r"^channel_weights: channel 1: a weight is a number >= 0"),
        ({"channels": True, "channel_tfs": {0: TransferFunction2D((0, 1), (0, 1))}},
         r"^channel_tfs: .*is 1D"),
        ({"channels": [3]}, r"^channels: .*channel 3 is not one of 0..2"),
        ({"channels": True, "labels": np.zeros(SHAPE, np.uint8)}, r"^channels: .*labels or with channels, not both"),
        ({"channels": True, "tf": TransferFunction2D((0, 1), (0, 1))}, r"^channels: .*got a 2D one"),
        ({"channels": True, "tf": ChannelTransferFunction([RED])}, r"^channels: the transfer function has 1 channels"),
    ],
)  # fmt: skip
def test_bad_channel_arguments_are_one_line_naming_them(rgb, kwargs, problem):
    with pytest.raises(VolrenError, match=problem) as info:
        volren.drawing(rgb / "rgb.vti", size=8, **kwargs)
    assert "\n" not in str(info.value)


def test_channels_of_a_volume_without_any_are_refused():
    with pytest.raises(
        VolrenError, match=r"^channels: volume has one field; give a UniformVolume with channels"
    ):
        volren.drawing(UniformVolume(field()), channels=True, size=8)


@pytest.mark.skipif(not reference_mixes_channels(), reason="reference does not mix channels yet")
def test_images_follow_the_model_channels_add_their_extinctions(rgb):
    """Max 1995's media add: two identical channels of weight 1 draw exactly as one of weight 2;
    a hidden channel as none; one channel as the plain field with its TF."""
    same = np.stack([field(), field()])
    two = UniformVolume(same[0], channels=PickedChannels(same))
    one = UniformVolume(same[0], channels=PickedChannels(same[:1]))
    kw = {"renderer": "reference", "size": 12, "azimuth": 30, "elevation": 20, "quality": None}
    doubled = volren.render(one, ChannelTransferFunction([RED], weights=[2.0]), **kw)
    added = volren.render(two, ChannelTransferFunction([RED, RED]), **kw)
    assert doubled[..., 3].max() > 0.1 and np.allclose(added, doubled, atol=1e-6)
    hidden = volren.render(two, ChannelTransferFunction([RED, RED]), hidden_channels=(1,), **kw)
    alone = volren.render(one, ChannelTransferFunction([RED]), **kw)
    assert np.allclose(hidden, alone, atol=1e-6)
    plain = volren.render(UniformVolume(field()), RED, **kw)
    assert np.allclose(alone, plain, atol=1e-5)
