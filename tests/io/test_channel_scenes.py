"""Scene files with a multi-channel volume: the channel pick and the TF per channel are saved and
read back, the volume read with those channels; scenes without channels read and write as before."""

from __future__ import annotations

import json

import numpy as np
import pytest
import pyvista as pv

from volren.errors import VolrenError
from volren.io import load_scene, save_scene
from volren.model.channels import ChannelTransferFunction
from volren.model.scene import OrbitView, Scene
from volren.model.transfer_function import TransferFunction1D

SHAPE = (3, 4, 5)  # nz, ny, nx


@pytest.fixture
def project(tmp_path):
    """data/rgb.vti (an array of 3 components: component c is 100 c + the point's index) and scenes/."""
    (tmp_path / "data").mkdir()
    (tmp_path / "scenes").mkdir()
    img = pv.ImageData(dimensions=SHAPE[::-1])
    index = np.arange(60, dtype=np.float32)
    img.point_data["rgb"] = np.stack([index + 100 * c for c in range(3)], axis=1)
    img.save(tmp_path / "data" / "rgb.vti")
    return tmp_path


def channel_tf() -> ChannelTransferFunction:
    red = TransferFunction1D([[200, 1, 0, 0]], [[200, 0], [259, 0.5]], 2.0)
    return ChannelTransferFunction([TransferFunction1D.ramp(0, 59, 0.3), red], weights=[1.0, 2.5],
                                   visible=[True, False])  # fmt: skip


def test_a_channel_scene_round_trips_and_reads_its_channels(project):
    path = project / "scenes" / "rgb.json"
    scene = Scene(
        str(project / "data" / "rgb.vti"), channel_tf(), OrbitView(30, 10), size=(16, 16), channels=(0, 2)
    )
    save_scene(scene, path)
    data = json.loads(path.read_text())
    assert data["volume"] == {"path": "../data/rgb.vti", "scalars": None, "channels": [0, 2]}
    assert data["transfer_function"]["kind"] == "channels"
    back = load_scene(path)
    assert back.channels == (0, 2)
    assert back.transfer_function.to_dict() == channel_tf().to_dict()
    assert back.volume.channels.indices == (0, 2)
    assert np.array_equal(
        back.volume.channels.values[1], np.arange(60, dtype=np.float32).reshape(SHAPE) + 200
    )
    # every channel: written as true
    save_scene(Scene(str(project / "data" / "rgb.vti"), channel_tf(), channels=True), path)
    assert json.loads(path.read_text())["volume"]["channels"] is True
    assert load_scene(path).volume.channels.count == 3


def test_a_scene_without_channels_is_written_as_before(project):
    path = project / "scenes" / "plain.json"
    save_scene(Scene(str(project / "data" / "rgb.vti"), TransferFunction1D.ramp(0, 1, 0.5)), path)
    data = json.loads(path.read_text())
    assert "channels" not in data["volume"]
    back = load_scene(path)
    assert back.channels is None and back.volume.channels is None and back.volume.scalars == "rgb:magnitude"


def test_a_tf_file_of_kind_channels_is_read_by_path(project):
    (project / "scenes" / "tf.json").write_text(json.dumps(channel_tf().to_dict()))
    scene = {
        "version": 1,
        "volume": {"path": "../data/rgb.vti", "channels": [1, 0]},
        "transfer_function": "tf.json",
    }
    (project / "scenes" / "s.json").write_text(json.dumps(scene))
    back = load_scene(project / "scenes" / "s.json")
    assert isinstance(back.transfer_function, ChannelTransferFunction) and back.transfer_function.weights == [
        1,
        2.5,
    ]
    assert back.volume.channels.indices == (1, 0)


@pytest.mark.parametrize("pick", ["all", [], [0, 0], [-1], [True], 3])
def test_a_bad_channel_pick_is_one_line_naming_the_scene(project, pick):
    scene = {"version": 1, "volume": {"path": "../data/rgb.vti", "channels": pick},
             "transfer_function": channel_tf().to_dict()}  # fmt: skip
    path = project / "scenes" / "bad.json"
    path.write_text(json.dumps(scene))
    with pytest.raises(VolrenError, match=r"bad\.json.*scene 'volume.channels' must") as info:
        load_scene(path)
    assert "\n" not in str(info.value)


def test_a_pick_the_file_does_not_have_names_the_scene(project):
    scene = {"version": 1, "volume": {"path": "../data/rgb.vti", "channels": [5]},
             "transfer_function": channel_tf().to_dict()}  # fmt: skip
    path = project / "scenes" / "five.json"
    path.write_text(json.dumps(scene))
    with pytest.raises(VolrenError, match=r"five\.json: volume: .*channel 5 is not one of 0..2"):
        load_scene(path)
