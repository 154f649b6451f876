"""2D transfer-function files: round trips (unknown keys kept), malformed files (one line naming
the file and the problem), and scenes holding a 2D TF inline or by path."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import pyvista as pv

from volren.errors import VolrenError
from volren.io import load_scene, load_transfer_function, save_scene, save_transfer_function
from volren.model import TFWidget, TransferFunction1D, TransferFunction2D
from volren.model.scene import OrbitView, Scene


def make_tf() -> TransferFunction2D:
    return TransferFunction2D(
        (0.0, 59.0),
        (0.0, 12.0),
        [
            TFWidget.gaussian((30.0, 2.0), (5.0, 1.5), (1.0, 0.2, 0.1), 0.7),
            TFWidget.box((10.0, 20.0), (0.0, 12.0), (0.1, 0.9, 0.2), 0.3),
            TFWidget.triangle(45.0, 6.0, 8.0, (0.2, 0.3, 1.0), 0.9),
        ],
        opacity_unit_distance=0.5,
    )


def write(path: Path, content) -> Path:
    path.write_text(content if isinstance(content, str) else json.dumps(content))
    return path


def test_round_trip_keeps_unknown_keys(tmp_path):
    tf = make_tf()
    tf.extra["editor"] = {"selected": 1}
    save_transfer_function(tf, tmp_path / "tf.json")
    saved = json.loads((tmp_path / "tf.json").read_text())
    assert saved["version"] == 1 and saved["kind"] == "2d" and len(saved["widgets"]) == 3
    saved["widgets"][0]["label"] = "skin"
    write(tmp_path / "tf.json", saved)
    back = load_transfer_function(tmp_path / "tf.json")
    assert isinstance(back, TransferFunction2D) and back == tf
    assert back.extra == {"editor": {"selected": 1}} and back.widgets[0].extra == {"label": "skin"}
    save_transfer_function(back, tmp_path / "again.json")
    assert json.loads((tmp_path / "again.json").read_text()) == saved
    # and 1D files still load as 1D
    save_transfer_function(TransferFunction1D.ramp(0, 1), tmp_path / "one.json")
    assert isinstance(load_transfer_function(tmp_path / "one.json"), TransferFunction1D)


GOOD = make_tf().to_dict()


def widget(i: int, **change):
    return {**GOOD["widgets"][i], **change}


@pytest.mark.parametrize(
    "content, fragment",
    [
        ({**GOOD, "version": 3}, "transfer function format version 3 is newer than this volren reads (up to 1)"),
        ({k: v for k, v in GOOD.items() if k != "widgets"}, "2D transfer function: missing 'widgets'"),
        ({k: v for k, v in GOOD.items() if k != "value_range"}, "2D transfer function: missing 'value_range'"),
        ({**GOOD, "widgets": {"type": "box"}}, "'widgets' must be a list, got dict"),
        ({**GOOD, "gradient_range": [2, 10]}, "gradient_range must be [0, gmax] with gmax > 0, got [2, 10]"),
        ({**GOOD, "value_range": [5]}, "value_range must be a list of 2 numbers"),
        ({**GOOD, "opacity_unit_distance": 0}, "opacity_unit_distance must be positive"),
        ({**GOOD, "widgets": ["box"]}, "widget 0: must be a JSON object, got str"),
        ({**GOOD, "widgets": [{"color": [1, 1, 1], "opacity": 1}]}, "widget 0: missing 'type'"),
        ({**GOOD, "widgets": [widget(0, type="ellipse")]}, "widget 0: unknown type 'ellipse'"),
        ({**GOOD, "widgets": [widget(0), {"type": "box", "color": [1, 1, 1], "opacity": 1}]},
         "widget 1: box widget: missing 'value_range'"),
        ({**GOOD, "widgets": [widget(0, width=[0, 1])]}, "widget 0: gaussian widget: width (standard deviations) must be positive"),
        ({**GOOD, "widgets": [widget(1, value_range=[20, 10])]}, "widget 0: box widget: value_range must be [lo, hi] with lo < hi"),
        ({**GOOD, "widgets": [widget(2, half_width=-1)]}, "widget 0: triangle widget: half_width must be positive"),
        ({**GOOD, "widgets": [widget(2, color=[1, 0.5, 3])]}, "widget 0: triangle widget: color values must lie in [0, 1]"),
        ({**GOOD, "widgets": [widget(2, color="red")]}, "color must be a list of 3 numbers"),
        ({**GOOD, "widgets": [widget(1, opacity="high")]}, "widget 0: box widget: opacity must be a number"),
        ('{"version": 1, "kind": "2d", "value_range": [0, 1], "gradient_range": [0, 1], '
         '"widgets": [{"type": "box", "value_range": [0, NaN], "gradient_range": [0, 1], '
         '"color": [1, 1, 1], "opacity": 1}]}', "value_range must be finite"),
    ],
)  # fmt: skip
def test_malformed_files_give_one_line_naming_file_and_problem(tmp_path, content, fragment):
    path = write(tmp_path / "bad.json", content)
    with pytest.raises(VolrenError) as info:
        load_transfer_function(path)
    message = str(info.value)
    assert message.startswith(f"{path}:") and fragment in message and "\n" not in message, message


@pytest.fixture
def project(tmp_path):
    img = pv.ImageData(dimensions=(5, 4, 3))
    img.point_data["density"] = np.arange(60, dtype=np.float32)
    img.save(tmp_path / "v.vti")
    save_transfer_function(make_tf(), tmp_path / "tf2d.json")
    return tmp_path


def test_scenes_hold_a_2d_tf_inline_or_by_path(project):
    tf = make_tf()
    save_scene(Scene(str(project / "v.vti"), tf, OrbitView(30, 20), renderer="reference"), project / "a.json")
    assert json.loads((project / "a.json").read_text())["transfer_function"]["kind"] == "2d"
    back = load_scene(project / "a.json")
    assert isinstance(back.transfer_function, TransferFunction2D) and back.transfer_function == tf
    assert back.volume is not None and back.renderer == "reference"

    write(project / "b.json", {"version": 1, "volume": {"path": "v.vti"}, "transfer_function": "tf2d.json"})
    assert load_scene(project / "b.json", load_volume=False).transfer_function == tf

    bad = {**tf.to_dict(), "widgets": [widget(0, center=[1])]}
    write(project / "c.json", {"version": 1, "volume": {"path": "v.vti"}, "transfer_function": bad})
    with pytest.raises(VolrenError) as info:
        load_scene(project / "c.json")
    message = str(info.value)
    assert message.startswith(f"{project / 'c.json'}:") and "widget 0: gaussian widget: center" in message
