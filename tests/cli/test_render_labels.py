"""`volren render` and `volren movie` with a label volume: --labels, --label-info, --label-tf and
--hide-labels, scene files with labels, and one-line errors naming the flag."""

from __future__ import annotations

import json

import numpy as np
import pytest
import pyvista as pv

import volren
from volren.cli.main import build_parser, main
from volren.cli.render_cmd import build_scene
from volren.io import save_scene, save_transfer_function
from volren.model.labels import PALETTE, LabelStyle, LabelTransferFunction
from volren.model.scene import Scene
from volren.model.transfer_function import TransferFunction1D
from volren.renderers.registry import registry

N = 8
BASE = TransferFunction1D([[0, 1, 1, 1]], [[0, 0.0], [21, 0.6]], 4.0)
BONE = TransferFunction1D.ramp(0, 21, 0.9)


def _save(values: np.ndarray, path) -> None:
    img = pv.ImageData(dimensions=values.shape[::-1])
    img.point_data["v"] = values.ravel()
    img.save(path)


def halves() -> np.ndarray:
    values = np.ones((N, N, N), np.uint8)
    values[:, :, N // 2 :] = 2
    return values


@pytest.fixture
def files(tmp_path):
    """ct.vti (8^3), seg.nii.gz (labels 1 and 2), base.json, bone.json, labels.json."""
    z, y, x = np.mgrid[0:N, 0:N, 0:N]
    _save((x + y + z).astype(np.float32), tmp_path / "ct.vti")
    _save(halves(), tmp_path / "seg.nii.gz")
    save_transfer_function(BASE, tmp_path / "base.json")
    save_transfer_function(BONE, tmp_path / "bone.json")
    info = {"version": 1, "labels": {"1": {"name": "liver", "opacity": 0.5}}}
    (tmp_path / "labels.json").write_text(json.dumps(info))
    return tmp_path


def scene_of(*argv: str) -> Scene:
    args = build_parser("render", every=False).parse_args(["render", *argv])
    return build_scene(args)[0]


def test_the_label_flags_make_the_scene(files):
    scene = scene_of(str(files / "ct.vti"), "--tf", str(files / "base.json"), "--renderer", "reference",
                     "--labels", str(files / "seg.nii.gz"), "--label-info", str(files / "labels.json"),
                     "--label-tf", f"2={files / 'bone.json'}", "--hide-labels", "0,7", "--hide-labels", "9")  # fmt: skip
    assert scene.labels_path == str(files / "seg.nii.gz")
    np.testing.assert_array_equal(scene.volume.labels.values, halves())
    assert scene.volume.labels.names == {1: "liver"}
    tf = scene.transfer_function
    assert isinstance(tf, LabelTransferFunction) and tf.base == BASE
    assert tf.styles == {1: LabelStyle(color=PALETTE[0], opacity=0.5), 2: LabelStyle(tf=BONE),
                         0: LabelStyle(visible=False), 7: LabelStyle(visible=False), 9: LabelStyle(visible=False)}  # fmt: skip


@pytest.mark.parametrize(("flags", "message"), [
    (["--label-tf", "bone.json"], "argument --label-tf: expected N=TF.json (a label and its transfer function), got "
                                  "'bone.json'"),
    (["--label-tf", "x=bone.json"], "argument --label-tf: the label before '=' must be a whole number in 0..65535, "
                                    "got 'x'"),
    (["--label-tf", "3="], "argument --label-tf: expected N=TF.json"),
    (["--hide-labels", "0,x"], "argument --hide-labels: expected labels N,M,... (whole numbers in 0..65535), got 'x' "
                               "in '0,x'"),
    (["--hide-labels", "70000"], "argument --hide-labels: expected labels N,M,..."),
])  # fmt: skip
def test_label_flags_that_say_no_label_are_usage_errors_naming_the_flag(capsys, flags, message):
    with pytest.raises(SystemExit) as exc:
        main(["render", "ct.vti", "-o", "x.png", *flags])
    assert exc.value.code == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith(f"volren render: error: {message}")


def test_label_inputs_that_cannot_be_used_are_one_line_errors_naming_the_flag(files, capsys):
    out = str(files / "x.png")
    ct = str(files / "ct.vti")
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float64)
    mesh = pv.UnstructuredGrid(np.array([4, 0, 1, 2, 3]), np.array([pv.CellType.TETRA]), points)
    mesh.point_data["v"] = np.arange(4.0)
    mesh.save(files / "m.vtu")
    _save(np.zeros((N, N, N - 1), np.uint8), files / "small.nii.gz")
    cases = [
        ([ct, "--labels", str(files / "none.nii.gz")], f"--labels: {files / 'none.nii.gz'}: no such file or folder"),
        ([ct, "--labels", str(files / "small.nii.gz")],
         f"--labels: {files / 'small.nii.gz'}: the label volume is 7x8x8 but ct.vti is 8x8x8"),
        ([str(files / "m.vtu"), "--labels", str(files / "seg.nii.gz")],
         "--labels: label volumes are for uniform grids; m.vtu is a tetrahedral mesh"),
        ([ct, "--hide-labels", "0"], "--hide-labels needs a label volume: give --labels"),
        ([ct, "--labels", str(files / "seg.nii.gz"), "--label-tf", f"1={files / 'none.json'}"],
         f"--label-tf: {files / 'none.json'}: no such file"),
        ([ct, "--labels", str(files / "seg.nii.gz"), "--label-info", str(files / "bone.json")],
         f"--label-info: {files / 'bone.json'}: unknown key(s)"),
    ]  # fmt: skip
    for argv, message in cases:
        assert main(["render", *argv, "-o", out, "--renderer", "reference"]) == 1, argv
        err = capsys.readouterr().err.splitlines()
        assert len(err) == 1 and err[0].startswith(f"volren: error: {message}"), (argv, err)


def test_a_scene_file_keeps_its_labels_and_tf_flags_go_over_them(files):
    tf = LabelTransferFunction(BASE, {2: LabelStyle(color=(0, 1, 0))})
    scene = Scene(str(files / "ct.vti"), tf, renderer="reference", labels_path=str(files / "seg.nii.gz"))
    save_scene(scene, files / "organs.json")
    again = scene_of("--scene", str(files / "organs.json"))
    np.testing.assert_array_equal(again.volume.labels.values, halves())
    assert again.transfer_function.to_dict() == tf.to_dict()
    # --tf replaces the base under the labels' styles; --hide-labels adds to them
    over = scene_of(
        "--scene", str(files / "organs.json"), "--tf", str(files / "bone.json"), "--hide-labels", "1"
    )
    assert over.transfer_function.base == BONE
    assert over.transfer_function.styles == {2: LabelStyle(color=(0, 1, 0)), 1: LabelStyle(visible=False)}
    # the scene's labels for another INPUT on the same grid
    other = scene_of(str(files / "ct.vti"), "--scene", str(files / "organs.json"))
    np.testing.assert_array_equal(other.volume.labels.values, halves())


@pytest.mark.filterwarnings("default::volren.errors.VolrenWarning")
def test_render_draws_labels_from_the_command_line(files, capsys):
    """With the reference: every label drawn with the volume's TF is the plain render (within
    float32), all hidden is black; until it draws labels, its refusal as one line."""
    common = [str(files / "ct.vti"), "--tf", str(files / "base.json"), "--renderer", "reference", "--size", "16",
              "--azimuth", "30", "--labels", str(files / "seg.nii.gz")]  # fmt: skip
    same = [*common, "--label-tf", f"1={files / 'base.json'}", "--label-tf", f"2={files / 'base.json'}"]
    support = registry.capabilities("reference").kinds["uniform"]
    if not support.labels:
        assert main(["render", *same, "--save-array", str(files / "a.npy")]) == 1
        assert "renderer reference does not draw label volumes" in capsys.readouterr().err
        return
    assert main(["render", *same, "--save-array", str(files / "a.npy")]) == 0
    plain = volren.render(files / "ct.vti", BASE, renderer="reference", size=16, azimuth=30)
    np.testing.assert_allclose(np.load(files / "a.npy"), plain, atol=1e-5)
    assert main(["render", *common, "--hide-labels", "1,2", "--save-array", str(files / "b.npy")]) == 0
    assert "every label in the label volume is hidden, so the image is black" in capsys.readouterr().err
    assert not np.load(files / "b.npy").any()


def test_a_movie_of_a_time_series_with_labels_is_refused(files, capsys):
    (files / "run").mkdir()
    z, y, x = np.mgrid[0:N, 0:N, 0:N]
    for step in range(2):
        _save((x + y + z + step).astype(np.float32), files / "run" / f"s{step}.vti")
    argv = ["movie", str(files / "run"), "--labels", str(files / "seg.nii.gz"), "-o", str(files / "m.gif"),
            "--renderer", "reference", "--tf", str(files / "base.json")]  # fmt: skip
    assert main(argv) == 1
    err = capsys.readouterr().err.splitlines()
    assert err[-1] == ("volren: error: --labels: a label volume lies on one volume's grid; a time series' movie "
                       "reads a volume a step")  # fmt: skip
