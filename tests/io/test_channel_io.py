"""Multi-channel volumes read from files (`load_volume(..., channels=...)`): an array's components
as channels, exactly as stored, named by the file's component names, picked and ordered, the volume's
values a view of the first channel, and one-line errors; without `channels`, the magnitude as before."""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv

from volren.errors import VolrenError, VolrenWarning
from volren.io import from_pyvista, load_volume
from volren.io.channel_io import PickedChannels, default_channel_tf, share_values
from volren.model.channels import MAX_CHANNELS

SHAPE = (5, 4, 3)  # z, y, x


def components(count: int) -> np.ndarray:
    """values[c, k, j, i] = 100 c + the point's index: every channel and voxel its own number."""
    index = np.arange(np.prod(SHAPE), dtype=np.float32).reshape(SHAPE)
    return np.stack([index + 100 * c for c in range(count)])


def save(path, stacked: np.ndarray, names: tuple[str, ...] = ()) -> None:
    img = pv.ImageData(dimensions=SHAPE[::-1])
    img.point_data["rgb"] = stacked.reshape(stacked.shape[0], -1).T
    for c, name in enumerate(names):
        img.point_data.GetArray("rgb").SetComponentName(c, name)
    img.save(path)


def test_components_read_as_channels_exactly_named_by_the_file(tmp_path):
    stacked = components(3)
    save(tmp_path / "named.vti", stacked, ("T1", "T2", "FLAIR"))
    volume = load_volume(tmp_path / "named.vti", channels=True)
    channels = volume.channels
    assert isinstance(channels, PickedChannels)
    assert np.array_equal(channels.values, stacked) and channels.values.dtype == np.float32
    assert channels.names == ("T1", "T2", "FLAIR") and channels.indices == (0, 1, 2)
    assert np.shares_memory(volume.values, channels.values)  # no second copy, across the reading process too
    assert np.array_equal(volume.values, stacked[0]) and volume.value_range == (0.0, 59.0)
    assert channels.value_ranges == ((0.0, 59.0), (100.0, 159.0), (200.0, 259.0))


def test_a_pick_keeps_those_channels_in_its_order_named_by_array_and_number(tmp_path):
    stacked = components(4)
    save(tmp_path / "four.vti", stacked)
    volume = load_volume(tmp_path / "four.vti", channels=[3, 1])
    assert np.array_equal(volume.channels.values, stacked[[3, 1]])
    assert volume.channels.names == ("rgb:3", "rgb:1") and volume.channels.indices == (3, 1)
    assert np.array_equal(volume.values, stacked[3])
    # without channels: the magnitude, as before
    plain = load_volume(tmp_path / "four.vti")
    assert plain.channels is None and plain.scalars == "rgb:magnitude"
    assert np.allclose(plain.values, np.sqrt((stacked.astype(np.float64) ** 2).sum(axis=0)))


def test_a_nan_in_one_channel_is_kept_and_said(tmp_path):
    stacked = components(2)
    stacked[1, 2, 1, 0] = np.nan
    save(tmp_path / "nan.vti", stacked)
    with pytest.warns(VolrenWarning, match=r"channel 'rgb:1' has 1 NaN or Inf values"):
        volume = load_volume(tmp_path / "nan.vti", channels=True)
    assert np.isnan(volume.channels.values[1, 2, 1, 0]) and volume.nonfinite_count == 0
    assert volume.channels.value_ranges[1] == (100.0, 159.0)


def test_bad_picks_are_one_line(tmp_path):
    save(tmp_path / "two.vti", components(2))
    path = tmp_path / "two.vti"
    for pick, problem in (([2], "channel 2 is not one of 0..1"), ([1, 1], "a channel is named twice"),
                          ([], "give at least one channel"), ("0", "give True")):  # fmt: skip
        with pytest.raises(VolrenError, match=problem) as info:
            load_volume(path, channels=pick)
        assert "\n" not in str(info.value) and str(path) in str(info.value)
    with pytest.raises(VolrenError, match=r"channels are an array's components; give the array's name"):
        load_volume(path, scalars="rgb:x", channels=True)


def test_a_scalar_array_and_too_many_components_are_refused_in_one_line(tmp_path):
    img = pv.ImageData(dimensions=SHAPE[::-1])
    img.point_data["v"] = np.arange(np.prod(SHAPE), dtype=np.float32)
    img.save(tmp_path / "scalar.vti")
    with pytest.raises(
        VolrenError, match=r"array 'v' has one component; channels come from an array of several"
    ):
        load_volume(tmp_path / "scalar.vti", channels=True)
    save(tmp_path / "many.vti", components(MAX_CHANNELS + 1))
    with pytest.raises(VolrenError, match=rf"{MAX_CHANNELS + 1} channels; at most {MAX_CHANNELS} are drawn"):
        load_volume(tmp_path / "many.vti", channels=True)
    picked = load_volume(tmp_path / "many.vti", channels=[MAX_CHANNELS, 0])
    assert picked.channels.indices == (MAX_CHANNELS, 0)
    with pytest.raises(VolrenError, match="headerless raw data holds one field"):
        load_volume(tmp_path / "many.vti", shape=(3, 4, 5), dtype="uint8", channels=True)


def test_a_pyvista_dataset_gives_channels_too():
    img = pv.ImageData(dimensions=SHAPE[::-1])
    stacked = components(2)
    img.point_data["rgb"] = stacked.reshape(2, -1).T
    volume = from_pyvista(img, channels=[1])
    assert np.array_equal(volume.channels.values, stacked[[1]]) and volume.channels.indices == (1,)


def test_the_vase_holds_four_identical_channels_and_the_stroke_three_contrasts(shared_data):
    vase = load_volume(shared_data / "multichannel" / "vase_4comp.vti", channels=True)
    assert vase.channels.count == 4 and vase.dimensions == (115, 101, 75)
    assert all(np.array_equal(vase.channels.values[c], vase.channels.values[0]) for c in range(1, 4))
    assert vase.channels.value_ranges[0] == (0.0, 239.0)
    stroke = load_volume(shared_data / "multichannel" / "stroke_t1_t2_flair.vti", channels=[2, 0])
    assert stroke.channels.value_ranges == ((0.0, 255.0), (0.0, 252.0))  # FLAIR, then T1 (MANIFEST.md)


def test_share_values_leaves_other_volumes_alone(tmp_path):
    save(tmp_path / "two.vti", components(2))
    volume = load_volume(tmp_path / "two.vti", channels=True)
    assert share_values(volume) is volume
    plain = load_volume(tmp_path / "two.vti")
    assert share_values(plain) is plain and plain.channels is None


def test_inactive_channels_are_hidden_in_the_default_look():
    stacked = components(3)
    channels = PickedChannels(stacked, active=(True, False, True))
    tf = default_channel_tf(channels)
    assert tf.visible == [True, False, True] and tf.weights == [1.0, 1.0, 1.0]
    rgb, alpha = tf.tfs[2].sample(np.array([200.0, 259.0]))
    assert np.allclose(alpha, [0.0, 0.2])  # a ramp over the channel's own range
