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
    with pytest.raises(
        VolrenError, match=r"v\.vti: -o would overwrite the input volume; choose another file$"
    ):
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
    scene.write_text(
        json.dumps({"version": 1, "volume": {"path": "ml.vti"}, "transfer_function": "ml.tf.json"})
    )
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


# ------------------------------------------------------------- outputs only where files belong
def make_node(path, kind: str) -> None:
    """A FIFO, a folder or (where this user may make one) a device node like /dev/null."""
    if kind == "FIFO":
        os.mkfifo(path)
    elif kind == "folder":
        path.mkdir()
    else:
        try:
            os.mknod(path, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
        except PermissionError:
            pytest.skip("this user may not make device nodes")


@pytest.mark.usefixtures("opengl")
@pytest.mark.parametrize("flag, name", [("-o", "out.png"), ("--save-array", "out.npy")])
@pytest.mark.parametrize(
    "kind, is_kind", [("FIFO", stat.S_ISFIFO), ("folder", stat.S_ISDIR), ("device", stat.S_ISCHR)]
)
def test_render_refuses_an_output_that_is_not_a_file_and_leaves_it(sample, tmp_path, capsys, flag, name, kind,
                                                                    is_kind):  # fmt: skip
    """A rename replaces whatever has the name: a FIFO or a device (`-o /dev/full`, as root)
    became a regular file, and the render said it had written it."""
    volume, tf = sample
    target = tmp_path / name
    make_node(target, kind)
    other = ["--save-array", str(tmp_path / "a.npy")] if flag == "-o" else ["-o", str(tmp_path / "a.png")]
    assert (
        main(["render", str(volume), "--tf", str(tf), "--size", "8", flag, str(target), *other, "--force"])
        == 1
    )
    assert (
        one_error_line(capsys)
        == f"volren: error: {target}: {flag} must be a file, not a {kind}; choose another path"
    )
    assert is_kind(target.lstat().st_mode) and not (tmp_path / "a.png").exists() and leftovers(tmp_path) == []


@pytest.mark.usefixtures("opengl")
def test_writes_go_through_a_link_to_its_file_and_keep_the_link(sample, tmp_path):
    volume, tf = sample
    (tmp_path / "files").mkdir()
    png, npy = tmp_path / "files" / "image.png", tmp_path / "files" / "image.npy"
    png.write_bytes(b"old")
    (tmp_path / "out.png").symlink_to(png)
    (tmp_path / "out.npy").symlink_to(npy)  # to a file not yet there
    argv = ["render", str(volume), "--tf", str(tf), "--size", "8", "-o", str(tmp_path / "out.png")]
    assert main([*argv, "--save-array", str(tmp_path / "out.npy")]) == 0
    assert (tmp_path / "out.png").is_symlink() and (tmp_path / "out.npy").is_symlink()
    assert png.read_bytes().startswith(b"\x89PNG") and np.load(npy).shape == (8, 8, 4)
    assert leftovers(tmp_path) == [] and leftovers(tmp_path / "files") == []


def test_the_library_writers_refuse_what_is_not_a_file(tmp_path):
    os.mkfifo(tmp_path / "pipe.png")
    with pytest.raises(VolrenError, match=r"pipe\.png: must be a file, not a FIFO; choose another path$"):
        save_image(np.ones((4, 4, 4), np.float32), tmp_path / "pipe.png")
    assert stat.S_ISFIFO((tmp_path / "pipe.png").lstat().st_mode) and leftovers(tmp_path) == []


@pytest.fixture
def zarr_output(tmp_path):
    pytest.importorskip("zarr", reason="volren[zarr] is part of the test set-up")
    volume, _ = sample_paths("marschner_lobb")
    return volume, tmp_path / "out.zarr"


def test_convert_force_refuses_an_output_folder_holding_its_input(zarr_output, capsys):
    volume, out = zarr_output
    out.mkdir()
    inside = shutil.copy(volume, out / "ml.vti")
    before = open(inside, "rb").read()
    assert main(["convert", str(inside), str(out), "--force"]) == 1
    assert one_error_line(capsys) == (f"volren: error: {out}: OUTPUT holds the input {inside}; replacing OUTPUT "
                                      f"would delete it; choose another folder")  # fmt: skip
    assert open(inside, "rb").read() == before and sorted(p.name for p in out.iterdir()) == ["ml.vti"]


def test_convert_force_writes_through_a_link_to_a_folder(zarr_output, capsys):
    volume, out = zarr_output
    real = out.with_name("real.zarr")
    assert main(["convert", str(volume), str(real)]) == 0
    out.symlink_to(real)
    assert main(["convert", str(volume), str(out), "--force", "--levels", "1"]) == 0
    assert out.is_symlink() and open_levels(real) == 1
    os.mkfifo(out.with_name("pipe.zarr"))
    assert main(["convert", str(volume), str(out.with_name("pipe.zarr")), "--force"]) == 1
    assert "OUTPUT must be a folder, not a FIFO" in capsys.readouterr().err


def open_levels(path) -> int:
    return len(json.loads((path / ".zattrs").read_text())["multiscales"][0]["datasets"])


@pytest.mark.parametrize("flag, name", [("-o", "out.png"), ("--save-array", "out.npy")])
def test_render_checks_the_folder_a_link_leads_to_before_rendering(sample, tmp_path, capsys, monkeypatch, flag,
                                                                    name):  # fmt: skip
    """Only the link's own folder was checked: a link into a missing folder failed once the frame
    was drawn, with Python's errno text and the temporary file's path."""
    import volren.cli.render_cmd as render_cmd

    volume, tf = sample
    monkeypatch.setattr(
        render_cmd, "build_scene", lambda args: pytest.fail("loaded before the outputs were checked")
    )
    link = tmp_path / name
    link.symlink_to(tmp_path / "gone" / name)
    other = ["--save-array", str(tmp_path / "a.npy")] if flag == "-o" else ["-o", str(tmp_path / "a.png")]
    assert main(["render", str(volume), "--tf", str(tf), "--size", "8", flag, str(link), *other]) == 1
    assert one_error_line(capsys) == f"volren: error: {link}: the folder {tmp_path / 'gone'} does not exist"
    assert link.is_symlink() and not (tmp_path / "gone").exists()
