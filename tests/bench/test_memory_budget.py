"""`python -m benchmarks.memory_budget`'s parts on a tiny volume: the NRRD it writes reads back as
the field it means, and a command's peak resident memory and last line come back from its child."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.memory_budget import peak, write_nrrd

pytest.importorskip("zarr", reason="volren[zarr] is part of the test set-up")


def test_the_volume_reads_back_and_a_commands_peak_is_measured(tmp_path):
    from volren.io import load_volume

    write_nrrd(tmp_path / "v.nrrd", 8)
    values = load_volume(tmp_path / "v.nrrd").values
    axis = np.arange(8, dtype=np.float32)
    y, x = np.meshgrid(axis, axis, indexing="ij")
    plane = 2000 + 1500 * np.sin(0.05 * x) * np.cos(0.04 * y)
    np.testing.assert_array_equal(values[3], (plane + 4000 * 3 / 8).astype(np.uint16))
    mib, seconds, said = peak(["convert", "v.nrrd", "v.zarr", "--memory", "64MB"], None, tmp_path)
    assert said == "v.nrrd: 8x8x8 uint16 -> v.zarr (1 levels, 64^3 bricks)"
    assert 20 < mib < 2000 and seconds > 0


def test_a_large_parent_does_not_count_in_its_childs_peak(tmp_path):
    """Linux keeps a process's largest resident size across exec, so a child started straight from
    a process holding 600 MB would read as 600 MB: the peak is the command's own (about 100 MB)."""
    held = np.ones(600 * 2**20 // 8)  # touched: resident in this process
    write_nrrd(tmp_path / "v.nrrd", 8)
    mib, _, said = peak(["convert", "v.nrrd", "v.zarr", "--memory", "64MB"], None, tmp_path)
    assert said.endswith("(1 levels, 64^3 bricks)") and 20 < mib < 400
    assert held.sum() == held.size
