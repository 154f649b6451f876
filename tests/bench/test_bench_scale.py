"""`python -m benchmarks.scale` on tiny volumes: it writes the procedural pyramids, measures each size in a
fresh process and the 1- and 2-worker cluster, and writes its table and model."""

from __future__ import annotations

import json

import numpy as np
import pytest

from benchmarks.procedural import ProceduralVolume
from benchmarks.scale import LayerCosts, composite_model, main

pytest.importorskip("distributed", reason="dask.distributed is part of the test set-up")


def test_the_procedural_volume_is_the_same_block_by_block():
    volume = ProceduralVolume(40)
    whole = volume[(slice(0, 40),) * 3]
    assert whole.dtype == np.uint16 and whole.shape == (40, 40, 40)
    assert whole.max() > 30000 and (whole == 0).mean() > 0.3  # structure inside, empty space outside
    block = volume[(slice(8, 24), slice(16, 40), slice(0, 9))]
    np.testing.assert_array_equal(block, whole[8:24, 16:40, 0:9])


def test_the_model_orders_the_strategies_as_icet_does():
    costs = LayerCosts(over_s_per_pixel=5e-9, transfer_s_per_byte=1e-9, latency_s=1e-4)
    small, large = composite_model(costs, 1 << 20, 8), composite_model(costs, 1 << 20, 1024)
    assert large["gather"] > 50 * small["gather"]  # gather grows with the workers
    assert large["binary_swap"] < 2 * small["binary_swap"] and large["radix_k"] < large["binary_swap"]


@pytest.mark.slow  # about 9 s
@pytest.mark.usefixtures("opengl")
@pytest.mark.filterwarnings("default::volren.errors.VolrenWarning")
def test_bench_scale_measures_and_writes_its_table(tmp_path, capsys):
    out = tmp_path / "out"
    argv = ["--sizes", "40,72", "--image", "48", "--frames", "2", "--cluster-size", "40",
            "--data", str(tmp_path / "data"), "--out", str(out), "--memory", "1MB"]  # fmt: skip
    assert main(argv) == 0
    result = json.loads((out / "scale.json").read_text())
    sizes = {(row["size"], row["level"]) for row in result["sizes"]}
    assert (40, 0) in sizes and (72, 0) in sizes
    for row in result["sizes"]:
        assert row["ms"] > 0 and row["peak_rss"] > 50 << 20 and 0 < row["cache_peak"] <= 1 << 20
        assert 0 < row["drawn"] <= row["bricks"]
    for workers in ("1", "2"):
        assert result["cluster"][workers]["ms"] > 0 and 0 <= result["cluster"][workers]["composite_share"] < 1
    table = (out / "scale.md").read_text()
    assert "| 72^3 (" in table and "radix-k" in table and "LocalCluster, 40^3" in table
    assert (tmp_path / "data" / "ml72.zarr").is_dir()
