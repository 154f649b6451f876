"""`python -m benchmarks.defaults_ab` and `benchmarks.objectorder_reach`: a row per scene with what
they promise, on a bundled sample at a small size."""

from __future__ import annotations

from benchmarks import defaults_ab, objectorder_reach


def _rows(text: str, prefix: str) -> list[list[str]]:
    return [
        [c.strip() for c in line.strip("|").split("|")]
        for line in text.splitlines()
        if line.startswith(prefix)
    ]


def test_no_options_against_vtk_gives_both_times_and_errors(capsys, tmp_path, renders_with_vtk):
    out = tmp_path / "ab.md"
    argv = ["--datasets", "marschner_lobb", "--size", "24", "--frames", "2", "--out", str(out)]
    assert defaults_ab.main(argv) == 0
    (row,) = _rows(capsys.readouterr().out, "| marschner_lobb/sample |")
    assert row[1].startswith("raycast") or ":" in row[1]  # auto's choice, named with its settings
    ours, vtk, ratio = float(row[2]), float(row[3]), float(row[4].rstrip("x"))
    assert ours > 0 and vtk > 0 and abs(ratio - vtk / ours) <= 0.051 * ratio + 0.05
    our_rmse, vtk_rmse, error_ratio = (float(c) for c in row[5:8])
    assert (
        0 < our_rmse < 0.1
        and 0 < vtk_rmse < 0.1
        and abs(error_ratio - our_rmse / vtk_rmse) < 0.01 * error_ratio + 0.01
    )
    assert "| marschner_lobb/sample |" in out.read_text()


def test_the_one_sided_reach_takes_fewer_cells_and_draws_the_same(capsys, shared_data):
    argv = [
        "--shared",
        str(shared_data.parent),
        "--scenes",
        "ironProt/opaque",
        "--size",
        "48",
        "--frames",
        "1",
    ]
    assert objectorder_reach.main(argv) == 0
    (row,) = _rows(capsys.readouterr().out, "| ironProt/opaque |")
    number = lambda cell: float(cell.split()[0])  # noqa: E731
    visible_both, visible_one, cells_both, cells_one = (number(c) for c in row[1:5])
    assert 0 < visible_one < visible_both and cells_one <= cells_both
    assert float(row[7]) <= 1e-6  # the same image
    assert objectorder_reach.oo.segment_reach is objectorder_reach.ONE_SIDED
