"""Scene files with a label volume: the label file's path (relative to the scene) and the TF per
label are saved and read back; scenes without labels read and write as before."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
import pyvista as pv

from volren.errors import VolrenError
from volren.io import load_scene, save_scene
from volren.model.labels import LabelStyle, LabelTransferFunction
from volren.model.scene import OrbitView, Scene
from volren.model.transfer_function import TransferFunction1D

SHAPE = (3, 4, 5)  # nz, ny, nx


def _save(values: np.ndarray, path) -> None:
    nz, ny, nx = values.shape
    img = pv.ImageData(dimensions=(nx, ny, nz), spacing=(1.0, 1.0, 2.0))
    img.point_data["v"] = values.ravel()
    img.save(path)


@pytest.fixture
def project(tmp_path):
    """data/ct.vti, its segmentation data/seg.nii.gz, and an empty scenes/ folder."""
    (tmp_path / "data").mkdir()
    (tmp_path / "scenes").mkdir()
    _save(np.arange(60, dtype=np.float32).reshape(SHAPE), tmp_path / "data" / "ct.vti")
    _save((np.arange(60).reshape(SHAPE) % 3).astype(np.uint8), tmp_path / "data" / "seg.nii.gz")
    return tmp_path


def label_tf() -> LabelTransferFunction:
    base = TransferFunction1D.ramp(0, 59, 0.5)
    own = TransferFunction1D([[0, 0, 1, 0]], [[0, 0], [59, 1]], 2.0)
    return LabelTransferFunction(base, {1: LabelStyle(color=(1, 0, 0), opacity=0.5), 2: LabelStyle(tf=own),
                                        0: LabelStyle(visible=False)})  # fmt: skip


def test_a_label_scene_round_trips_with_its_label_file_relative(project):
    scene_path = project / "scenes" / "organs.json"
    tf = label_tf()
    scene = Scene(str(project / "data" / "ct.vti"), tf, OrbitView(30, 10), size=(16, 16),
                  labels_path=str(project / "data" / "seg.nii.gz"))  # fmt: skip
    save_scene(scene, scene_path)
    saved = json.loads(scene_path.read_text())
    assert saved["version"] == 1
    assert saved["volume"] == {"path": "../data/ct.vti", "scalars": None, "labels": "../data/seg.nii.gz"}
    assert saved["transfer_function"] == tf.to_dict()
    moved = project.parent / f"{project.name}-moved"  # tmp_path.parent is shared by every test
    shutil.copytree(project, moved)
    back = load_scene(moved / "scenes" / "organs.json")
    assert back.labels_path == str(moved / "data" / "seg.nii.gz")
    assert isinstance(back.transfer_function, LabelTransferFunction)
    assert back.transfer_function.to_dict() == tf.to_dict()
    assert back.volume is not None and back.volume.labels is not None
    np.testing.assert_array_equal(back.volume.labels.values, np.arange(60).reshape(SHAPE) % 3)
    assert back.to_dict() == {**scene.to_dict(), "volume": {**scene.to_dict()["volume"],
                                                             "path": back.volume_path, "labels": back.labels_path}}  # fmt: skip


def test_an_old_scene_reads_and_writes_as_before(project):
    """A scene of the format before labels: no labels, its TF a 1D TF, and written back without a
    'labels' key (the format's version stays 1)."""
    old = {"version": 1, "volume": {"path": "../data/ct.vti", "scalars": None},
           "transfer_function": TransferFunction1D.ramp(0, 59, 0.5).to_dict(), "size": [16, 16]}  # fmt: skip
    (project / "scenes" / "old.json").write_text(json.dumps(old))
    scene = load_scene(project / "scenes" / "old.json")
    assert scene.labels_path is None and scene.volume is not None and scene.volume.labels is None
    assert isinstance(scene.transfer_function, TransferFunction1D)
    save_scene(scene, project / "scenes" / "again.json")
    assert json.loads((project / "scenes" / "again.json").read_text())["volume"] == old["volume"]


def test_a_scene_tf_file_may_be_a_tf_per_label(project):
    (project / "scenes" / "organs_tf.json").write_text(json.dumps(label_tf().to_dict()))
    scene = {"version": 1, "volume": {"path": "../data/ct.vti", "labels": "../data/seg.nii.gz"},
             "transfer_function": "organs_tf.json"}  # fmt: skip
    (project / "scenes" / "s.json").write_text(json.dumps(scene))
    back = load_scene(project / "scenes" / "s.json")
    assert isinstance(back.transfer_function, LabelTransferFunction)
    assert back.transfer_function.to_dict() == label_tf().to_dict()


@pytest.mark.parametrize(("labels", "problem"), [
    ("../data/none.nii.gz", "labels: .*none.nii.gz: no such file"),
    (7, "scene 'volume.labels' must be a string, got 7"),
])  # fmt: skip
def test_a_scene_with_bad_labels_is_one_line_naming_the_scene(project, labels, problem):
    scene = {"version": 1, "volume": {"path": "../data/ct.vti", "labels": labels},
             "transfer_function": label_tf().to_dict()}  # fmt: skip
    path = project / "scenes" / "bad.json"
    path.write_text(json.dumps(scene))
    with pytest.raises(VolrenError, match=rf"^{path}: {problem}"):
        load_scene(path)


def test_a_scene_with_labels_on_another_grid_says_both_sizes(project):
    _save(np.zeros((3, 4, 4), np.uint8), project / "data" / "small.nii.gz")
    scene = {"version": 1, "volume": {"path": "../data/ct.vti", "labels": "../data/small.nii.gz"},
             "transfer_function": label_tf().to_dict()}  # fmt: skip
    path = project / "scenes" / "bad.json"
    path.write_text(json.dumps(scene))
    with pytest.raises(
        VolrenError, match=r"labels: .*small.nii.gz: the label volume is 4x4x3 but ct.vti is 5x4x3"
    ):
        load_scene(path)
