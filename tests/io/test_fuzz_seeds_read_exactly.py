"""Every valid file the fuzz corpus starts from reads back exactly the values and geometry that
were written, in every format: the oracle that caught vtkNrrdReader returning unfilled memory for
ASCII data, which rendered without a word and looked plausible at 24x24."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from benchmarks.fuzz.seeds import SPACING, Seed, grid_values, mesh, seeds
from volren.errors import VolrenWarning
from volren.io import load_volume
from volren.model.volume import TetVolume, UniformVolume

#: Formats that store no origin (SLC) or no spacing: what they read back instead.
_NO_ORIGIN = {"slc-rle", "slc-raw", "raw"}
_NO_SPACING = {"raw"}


def _load(seed: Seed, folder: Path) -> UniformVolume | TetVolume:
    for name, data in seed.files.items():
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_bytes(data)
    target = folder / seed.target
    if seed.name == "raw":
        return load_volume(target, shape=(8, 7, 6), dtype="int16")
    return load_volume(target)


@pytest.mark.parametrize("seed", seeds(), ids=lambda s: s.name)
def test_seed_reads_back_what_was_written(tmp_path, seed):
    if seed.kind == "mesh":  # five tetrahedra per cube, some of them written inside out
        with pytest.warns(VolrenWarning, match="reoriented 24 inverted"):
            volume = _load(seed, tmp_path)
        points, tets, values = mesh()
        assert isinstance(volume, TetVolume)
        assert np.array_equal(volume.points, points) and np.array_equal(volume.values, values)
        return
    volume = _load(seed, tmp_path)
    assert isinstance(volume, UniformVolume)
    expected = grid_values() // 8 if seed.name.startswith("slc") else grid_values()
    assert np.array_equal(volume.values, expected.clip(0, 255) if seed.name.startswith("slc") else expected)
    assert volume.spacing == pytest.approx((1.0, 1.0, 1.0) if seed.name in _NO_SPACING else SPACING)
    assert volume.origin == pytest.approx((0.0, 0.0, 0.0) if seed.name in _NO_ORIGIN else (1.0, -2.0, 0.5))
