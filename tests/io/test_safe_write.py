"""No file destroyed: writes replace the old file only when complete, and an output that is one of
the inputs is refused (unless --force)."""

from __future__ import annotations

import json
import os
import shutil
import stat

import numpy as np
import pytest

from volren.cli.main import main
from volren.errors import VolrenError
from volren.io import save_image
from volren.io.safe_write import refuse_overwriting_inputs, write_atomically
from volren.samples import sample_paths


def leftovers(folder) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if ".partial" in p.name)


def test_a_failed_write_leaves_the_old_file_and_no_partial_one(tmp_path):
    target = tmp_path / "volume.vti"
    target.write_bytes(b"the good old file")

    def half_then_fail(tmp):
        tmp.write_bytes(b"half a fi")
        raise OSError(28, "No space left on device")

    with pytest.raises(OSError, match="No space"):
        write_atomically(target, half_then_fail)
    assert target.read_bytes() == b"the good old file"
    assert leftovers(tmp_path) == []


def test_a_complete_write_replaces_the_file_keeping_its_permissions(tmp_path):
    target = tmp_path / "image.png"
    target.write_bytes(b"old")
    os.chmod(target, 0o640)
    write_atomically(target, lambda tmp: tmp.write_bytes(b"new"))
    assert target.read_bytes() == b"new" and stat.S_IMODE(target.stat().st_mode) == 0o640
    fresh = tmp_path / "fresh.png"
    write_atomically(fresh, lambda tmp: tmp.write_bytes(b"x"))
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(fresh.stat().st_mode) == 0o666 & ~umask  # not mkstemp's private 0600
    assert leftovers(tmp_path) == []


def test_save_image_failing_inside_the_encoder_keeps_the_old_png(tmp_path, monkeypatch):
    target = tmp_path / "out.png"
    save_image(np.ones((4, 4, 4), np.float32), target)
    before = target.read_bytes()
    from PIL import Image

    def broken_save(self, fp, *args, **kwargs):
        with open(fp, "wb") as f:
            f.write(b"\x89PNG trunc")
        raise OSError("encoder failed")

    monkeypatch.setattr(Image.Image, "save", broken_save)
    with pytest.raises(VolrenError, match="out.png: cannot write the PNG"):
        save_image(np.zeros((4, 4, 4), np.float32), target)
    assert target.read_bytes() == before and leftovers(tmp_path) == []


def test_outputs_that_are_inputs_or_each_other_are_refused(tmp_path):
    volume = tmp_path / "v.vti"
    volume.write_bytes(b"data")
    with pytest.raises(VolrenError, match=r"v\.vti: -o would overwrite the input volume; choose another file$"):
        refuse_overwriting_inputs([("-o", str(volume))], [("input volume", str(volume))])
    link = tmp_path / "link.vti"
    link.symlink_to(volume)
    with pytest.raises(VolrenError, match="would overwrite"):
        refuse_overwriting_inputs([("-o", link)], [("input volume", volume)])
    with pytest.raises(VolrenError, match="--save-array and -o name the same file"):
        refuse_overwriting_inputs([("-o", tmp_path / "a.png"), ("--save-array", tmp_path / "a.png")], [])
    refuse_overwriting_inputs([("-o", tmp_path / "a.png")], [("input volume", volume), ("--tf file", None)])


@pytest.fixture
def sample(tmp_path):
    volume, tf = sample_paths("marschner_lobb")
    return shutil.copy(volume, tmp_path / "ml.vti"), shutil.copy(tf, tmp_path / "ml.tf.json")


def one_error_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


@pytest.mark.parametrize("which", ["volume", "tf"])
def test_render_refuses_to_overwrite_its_inputs(sample, capsys, which):
    volume, tf = sample
    target = volume if which == "volume" else tf
    before = open(target, "rb").read()
    assert main(["render", str(volume), "--tf", str(tf), "-o", str(target), "--size", "8"]) == 1
    line = one_error_line(capsys)
    assert line.startswith(f"volren: error: {target}: -o would overwrite") and "--force" in line
    assert open(target, "rb").read() == before


@pytest.mark.usefixtures("opengl")
def test_render_refuses_the_scenes_volume_and_force_overrides(sample, tmp_path, capsys):
    volume, tf = sample
    scene = tmp_path / "s.json"
    scene.write_text(json.dumps({"version": 1, "volume": {"path": "ml.vti"}, "transfer_function": "ml.tf.json"}))
    before = open(volume, "rb").read()
    assert main(["render", "--scene", str(scene), "-o", str(volume), "--size", "8"]) == 1
    assert "would overwrite the scene's volume" in one_error_line(capsys)
    assert open(volume, "rb").read() == before
    assert main(["render", str(volume), "--tf", str(tf), "-o", str(volume), "--size", "8", "--force"]) == 0
    assert open(volume, "rb").read().startswith(b"\x89PNG")  # asked for, so done


def test_view_refuses_a_screenshot_over_its_input(sample, capsys):
    volume, _ = sample
    assert main(["view", str(volume), "--screenshot", str(volume)]) == 1
    assert "--screenshot would overwrite the input" in one_error_line(capsys)
