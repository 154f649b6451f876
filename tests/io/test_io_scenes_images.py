"""Scene files (paths relative to the scene) and image output (PNG compositing, .npy)."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
import pyvista as pv
from PIL import Image

from volren.errors import VolrenError
from volren.io import (
    load_scene,
    load_transfer_function,
    save_array,
    save_image,
    save_scene,
    save_transfer_function,
)
from volren.model.scene import OrbitView, Scene
from volren.model.transfer_function import TransferFunction1D


@pytest.fixture
def project(tmp_path):
    """data/v.vti, tfs/ramp.json and an empty scenes/ folder."""
    (tmp_path / "data").mkdir()
    (tmp_path / "tfs").mkdir()
    (tmp_path / "scenes").mkdir()
    img = pv.ImageData(dimensions=(5, 4, 3))
    img.point_data["density"] = np.arange(60, dtype=np.float32)
    img.point_data["other"] = np.zeros(60, dtype=np.float32)
    img.save(tmp_path / "data" / "v.vti")
    save_transfer_function(TransferFunction1D.ramp(0, 59, 0.5), tmp_path / "tfs" / "ramp.json")
    return tmp_path


def test_scene_round_trip_with_relative_paths(project):
    scene_path = project / "scenes" / "a.json"
    tf = TransferFunction1D([[0, 1, 0, 0], [59, 0, 0, 1]], [[0, 0], [59, 0.7]], 2.0)
    view = OrbitView(30, 20, 1.5)
    volume = str(project / "data" / "v.vti")
    scene = Scene(volume, tf, view, scalars="density", size=(64, 48), extra={"comment": "kept"})
    save_scene(scene, scene_path)
    saved = json.loads(scene_path.read_text())
    assert saved["volume"] == {"path": "../data/v.vti", "scalars": "density"}
    assert saved["transfer_function"]["opacity"] == [[0, 0], [59, 0.7]]  # inline
    # the whole folder moves: relative paths still resolve
    moved = project.parent / "moved"
    shutil.copytree(project, moved)
    back = load_scene(moved / "scenes" / "a.json")
    assert back.volume_path == str(moved / "data" / "v.vti")
    assert back.volume is not None and back.volume.value_range == (0.0, 59.0)
    assert back.transfer_function == tf
    assert (back.camera, back.size, back.scalars, back.extra) == (
        scene.camera,
        (64, 48),
        "density",
        {"comment": "kept"},
    )


def test_scene_with_tf_path_and_without_loading(project):
    scene_path = project / "scenes" / "b.json"
    volume = {"path": "../data/v.vti", "scalars": "other"}
    scene_path.write_text(
        json.dumps({"version": 1, "volume": volume, "transfer_function": "../tfs/ramp.json"})
    )
    scene = load_scene(scene_path, load_volume=False)
    assert scene.volume is None
    assert scene.transfer_function == load_transfer_function(project / "tfs" / "ramp.json")
    save_scene(scene, project / "c.json")  # saving writes the TF inline, the path relative to c.json
    saved = json.loads((project / "c.json").read_text())
    assert saved["volume"]["path"] == "data/v.vti"
    assert isinstance(saved["transfer_function"], dict)


TF = "../tfs/ramp.json"


@pytest.mark.parametrize(
    "content, fragment",
    [
        ("{", "invalid JSON at line 1"),
        ("[]", "a scene must be a JSON object, got list"),
        ({"version": 1, "volume": {"path": "v.vti"}}, "scene has no 'transfer_function'"),
        (
            {"version": 1, "kind": "1d", "color": [[0, 1, 1, 1]], "opacity": [[0, 1]]},
            "this is a transfer function, not a scene: give it with --tf",
        ),
        ({"version": 9, "transfer_function": "x.json"}, "transfer function: "),
        (
            {"version": 9, "transfer_function": {"color": [[0, 1, 1, 1]], "opacity": [[0, 1]]}},
            "version 9 is newer",
        ),
        ({"version": 1, "transfer_function": "../tfs/missing.json"}, "transfer function: "),
        ({"version": 1, "volume": {"path": "../data/missing.vti"}, "transfer_function": TF}, "volume: "),
        (
            {"version": 1, "volume": {"path": "../data/v.vti", "scalars": "no"}, "transfer_function": TF},
            "array named 'no'",
        ),
    ],
)
def test_scene_errors_name_the_scene_file(project, content, fragment):
    path = project / "scenes" / "bad.json"
    path.write_text(content if isinstance(content, str) else json.dumps(content))
    with pytest.raises(VolrenError) as info:
        load_scene(path)
    message = str(info.value)
    assert message.startswith(f"{path}: ") and fragment in message, message


def test_scene_errors_name_the_inner_file_too(project):
    path = project / "scenes" / "s.json"
    path.write_text(
        json.dumps(
            {"version": 1, "volume": {"path": "../data/missing.vti"}, "transfer_function": "../tfs/ramp.json"}
        )
    )
    with pytest.raises(VolrenError, match=r"s.json: volume: .*missing.vti: no such file or folder"):
        load_scene(path)


@pytest.fixture
def series(project):
    """series/t0.vti ... t2.vti, whose values are the step number plus a ramp below 1."""
    (project / "series").mkdir()
    for step in range(3):
        img = pv.ImageData(dimensions=(3, 3, 3))
        img.point_data["density"] = step + np.arange(27, dtype=np.float32) / 27
        img.save(project / "series" / f"t{step}.vti")
    return project / "series"


def test_a_scene_on_a_time_series_reads_its_step_from_the_series_and_saves_it_relative(project, series):
    """The series and step decide the volume ("volume.path" is for readers without series), and
    both paths are written relative to the scene, so the folder can move."""
    path = project / "scenes" / "t.json"
    path.write_text(json.dumps({"version": 1, "time_series": {"path": "../series", "step": 2},
                                "volume": {"path": "../series/t0.vti"}, "transfer_function": TF}))  # fmt: skip
    scene = load_scene(path)
    assert scene.volume_path == str(series / "t2.vti") and scene.volume.value_range[0] == 2.0
    assert scene.extra["time_series"] == {"path": str(series), "step": 2}
    save_scene(scene, project / "again.json")
    saved = json.loads((project / "again.json").read_text())
    assert (
        saved["time_series"] == {"path": "series", "step": 2} and saved["volume"]["path"] == "series/t2.vti"
    )


@pytest.mark.parametrize(
    "entry, fragment",
    [
        ("../series", "'time_series' must be an object with a 'path'"),
        ({"path": "../series"}, "and a 'step' (an integer from 0)"),
        ({"path": "../series", "step": -1}, "and a 'step' (an integer from 0)"),
        ({"path": "../series", "step": True}, "and a 'step' (an integer from 0)"),
        ({"path": "../series", "step": 3}, "time series step 3: series has steps 0 to 2"),
        ({"path": "../gone.pvd", "step": 0}, "gone.pvd: no such file or folder"),
    ],
)
def test_a_bad_time_series_in_a_scene_is_one_line_naming_the_scene(project, series, entry, fragment):
    path = project / "scenes" / "bad.json"
    path.write_text(json.dumps({"version": 1, "time_series": entry, "transfer_function": TF}))
    with pytest.raises(VolrenError) as info:
        load_scene(path, load_volume=False)
    message = str(info.value)
    assert message.startswith(f"{path}: ") and fragment in message and "\n" not in message, message


# ------------------------------------------------------------------------------------- images


def premultiplied() -> np.ndarray:
    """2x3 image: transparent, half-transparent red, opaque green; out-of-range and NaN values."""
    rgba = np.zeros((2, 3, 4), np.float32)
    rgba[0, 1] = [0.5, 0.0, 0.0, 0.5]
    rgba[0, 2] = [0.0, 1.0, 0.0, 1.0]
    rgba[1, 0] = [1.5, -0.2, np.nan, 1.0]
    rgba[1, 1] = [0.25, 0.25, 0.25, 0.25]
    return rgba


def test_png_over_background(tmp_path):
    save_image(premultiplied(), tmp_path / "a.png", background=(0.0, 0.0, 1.0))
    png = np.asarray(Image.open(tmp_path / "a.png"))
    assert png.shape == (2, 3, 3) and png.dtype == np.uint8
    assert png[0, 0].tolist() == [0, 0, 255]  # all background
    assert png[0, 1].tolist() == [128, 0, 128]  # 0.5 red + 0.5 blue: round(127.5) = 128
    assert png[0, 2].tolist() == [0, 255, 0]
    assert png[1, 0].tolist() == [255, 0, 0]  # clipped; NaN -> 0
    assert png[1, 1].tolist() == [64, 64, 255]  # 0.25 + 0.75 * bg
    save_image(premultiplied(), tmp_path / "black.png")
    assert np.asarray(Image.open(tmp_path / "black.png"))[0, 1].tolist() == [128, 0, 0]


def test_png_transparent_has_straight_colour(tmp_path):
    save_image(premultiplied(), tmp_path / "t.png", transparent=True)
    png = np.asarray(Image.open(tmp_path / "t.png"))
    assert png.shape == (2, 3, 4)
    assert png[0, 0].tolist() == [0, 0, 0, 0]
    assert png[0, 1].tolist() == [255, 0, 0, 128]  # 0.5 / 0.5 = 1.0 red at half alpha
    assert png[1, 1].tolist() == [255, 255, 255, 64]


def test_npy_round_trip_and_bad_images(tmp_path):
    image = premultiplied()
    save_array(image, tmp_path / "a.npy")
    back = np.load(tmp_path / "a.npy")
    assert back.dtype == np.float32
    np.testing.assert_array_equal(back, image)
    with pytest.raises(VolrenError, match=r"an image must be an \(H, W, 4\) RGBA array, got shape \(2, 3\)"):
        save_image(np.zeros((2, 3)), tmp_path / "x.png")
    with pytest.raises(VolrenError, match="must be float RGBA"):
        save_image(np.zeros((2, 3, 4), np.uint8), tmp_path / "x.png")
    with pytest.raises(VolrenError, match="background must be three numbers"):
        save_image(image, tmp_path / "x.png", background=(1, 1))
    with pytest.raises(VolrenError, match="cannot write the PNG"):
        save_image(image, tmp_path / "no-such-folder" / "x.png")
    with pytest.raises(VolrenError, match="cannot write"):
        save_array(image, tmp_path / "no-such-folder" / "x.npy")


def test_a_scene_camera_with_a_zero_view_up_is_refused_naming_the_file(tmp_path):
    scene = {"version": 1, "transfer_function": TransferFunction1D.ramp(0, 1).to_dict(),
             "camera": {"position": [0, 0, 5], "focal_point": [0, 0, 0], "view_up": [0, 0, 0]}}  # fmt: skip
    path = tmp_path / "up.json"
    path.write_text(json.dumps(scene))
    with pytest.raises(VolrenError, match=r"^.*up\.json: camera view up is the zero vector"):
        load_scene(path, load_volume=False)
