"""`python -m benchmarks.gpu`: the scenes travel as arrays and come back as a table (run here on
llvmpipe, at a small size)."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

from benchmarks import gpu

pytestmark = pytest.mark.usefixtures("opengl")  # fails, naming the packages, where EGL cannot work


def test_export_then_run(shared_data, tmp_path, monkeypatch):
    monkeypatch.setattr(gpu, "ERROR_SIZE", 32)
    monkeypatch.setenv("VOLREN_REFERENCE_CACHE", str(tmp_path / "cache"))
    arrays = tmp_path / "arrays"
    gpu.export(shared_data.parent, arrays, ["spx"])
    (dataset,) = gpu.exported(arrays)
    assert dataset.name == "spx" and dataset.kind == "tet"
    volume = dataset.load()
    # the exported arrays are the loaded ones, so the reference images keep their keys
    assert len(list((arrays / "reference").glob("*.npy"))) == len(dataset.tf_paths) == 3
    assert volume.points.dtype == np.float64 and len(volume.tets) > 1000

    out = tmp_path / "out"
    assert (
        gpu.main(["run", "--arrays", str(arrays), "--out", str(out), "--sizes", "16,32", "--frames", "1"])
        == 0
    )
    rows = list(csv.DictReader((out / "gpu.csv").open()))
    assert len(rows) == 3 * 2 * 2  # TFs x configurations x sizes
    for row in rows:
        assert math.isfinite(float(row["ms"])) and float(row["cell_steps"]) > 0
        if row["size"] == "32":
            assert float(row["rmse"]) < 0.01  # tetra's table path against the reference
    text = (out / "gpu.md").read_text()
    assert text.count("| spx |") == 3 * 2  # one line per TF and configuration, sizes side by side
    assert "ms 16 | GPU ms 16 | ms 32 | GPU ms 32" in text


def test_the_configurations():
    assert {c.renderer for c in gpu.configs("tet")} == {"tetra"}
    assert all(c.settings.options["backend"] == "gl" for c in gpu.configs("tet"))
    assert {c.renderer for c in gpu.configs("uniform")} == {"slicer"}
    assert len({c.label for c in gpu.configs("uniform")}) == len(gpu.configs("uniform"))
