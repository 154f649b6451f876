"""`benchmarks.tf2d_drag`: a row per grid scene, each with both tables' times and the smaller
table's difference from the full one."""

from __future__ import annotations

from benchmarks import tf2d_drag
from volren.bench.datasets import hard_datasets


def test_each_hard_grid_gets_a_row_with_both_tables(capsys):
    assert tf2d_drag.main(["--size", "20", "--frames", "2"]) == 0
    out = capsys.readouterr().out
    rows = [line for line in out.splitlines() if line.startswith("| hard_")]
    grids = [name for name, d in hard_datasets().items() if d.kind == "uniform"]
    assert [row.split("|")[1].strip() for row in rows] == grids
    for row in rows:
        full_ms, small_ms, ratio, largest, rmse = (float(cell) for cell in row.split("|")[2:7])
        assert full_ms > 0 and small_ms > 0 and ratio > 0
        assert 0.0 <= rmse <= largest <= 1.0
