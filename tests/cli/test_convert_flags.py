"""`volren convert`'s flags and OUTPUT checked before the input is read, each refusal one line
naming the flag or OUTPUT as given (the pyramid writer's own checks named neither)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from volren.cli.main import main
from volren.io import save_volume
from volren.model.pyramid import max_levels
from volren.model.volume import UniformVolume

pytest.importorskip("zarr", reason="volren[zarr] is part of the test set-up")


@pytest.fixture(params=["v.vti", "v.nrrd"])
def grid(request, tmp_path, monkeypatch) -> str:
    """An 8x7x6 grid, read whole (.vti) or streamed (raw NRRD), in the current folder (so that
    paths are as a user types them)."""
    monkeypatch.chdir(tmp_path)
    values = np.arange(6 * 7 * 8, dtype="<u2").reshape(6, 7, 8)
    if request.param.endswith(".vti"):
        save_volume(UniformVolume(values), request.param)
    else:
        header = b"NRRD0004\ntype: uint16\ndimension: 3\nsizes: 8 7 6\nendian: little\nencoding: raw\n\n"
        Path(request.param).write_bytes(header + values.tobytes())
    return request.param


def one_error_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


@pytest.mark.parametrize("chunks", ["1", "1025", "4294967296", "99999999999", "99999999999999999999"])
def test_chunks_outside_what_the_writer_takes_is_a_usage_error_naming_chunks(grid, capsys, chunks):
    """The writer refused them after the load, naming OUTPUT's path and not --chunks."""
    with pytest.raises(SystemExit) as exc:
        main(["convert", grid, "out.zarr", "--chunks", chunks])
    assert exc.value.code == 2
    assert one_error_line(capsys) == (f"volren convert: error: argument --chunks: expected 2 to 1024 samples a side, "
                                      f"got '{chunks}' (see volren convert --help)")  # fmt: skip


@pytest.mark.parametrize("levels", ["3", "99", "4294967296", "99999999999999999999"])
def test_more_levels_than_the_grid_has_are_refused_naming_levels(grid, capsys, levels):
    """An 8x7x6 grid halves once (to 4x3x3); the writer said "level 2 would have fewer than 2
    samples along an axis", naming neither --levels nor the input."""
    assert main(["convert", grid, "out.zarr", "--levels", levels]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == (f"volren: error: {grid}: --levels {levels} is too many: its 8x7x6 grid has at most 2 "
                       "levels (each halves it, down to 2 samples an axis)")  # fmt: skip
    assert os.listdir() == [grid]


def test_the_levels_a_grid_allows_end_before_an_axis_drops_below_two_samples():
    assert [
        max_levels(shape) for shape in ((6, 7, 8), (3, 100, 100), (4, 4, 4), (21, 30, 37), (512, 512, 8))
    ] == [2, 1, 2, 4, 3]


def test_all_the_levels_a_grid_allows_are_written(grid, capsys):
    assert main(["convert", grid, "out.zarr", "--levels", "2"]) == 0
    assert capsys.readouterr().out.strip() == f"{grid}: 8x7x6 uint16 -> out.zarr (2 levels, 64^3 bricks)"


def test_an_output_linked_into_a_missing_folder_is_refused_before_the_load(grid, capsys, monkeypatch):
    """The writer found the missing folder only after reading the input whole, and began with the
    link's resolved target, not OUTPUT as given."""
    import volren.io

    monkeypatch.setattr(
        volren.io, "load_volume", lambda *a, **k: pytest.fail("read before OUTPUT was checked")
    )
    os.symlink("gone/real.zarr", "out.zarr")
    assert main(["convert", grid, "out.zarr"]) == 1
    gone = Path("gone").resolve()
    assert one_error_line(capsys) == f"volren: error: out.zarr: the folder {gone} does not exist"
    assert Path("out.zarr").is_symlink() and not gone.exists()
