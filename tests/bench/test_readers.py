"""`python -m benchmarks.readers` prints one row per file with volren's values equal to VTK's."""

from __future__ import annotations

from benchmarks import readers


def test_rows_for_a_shared_dataset_and_a_written_format(shared_data, capsys):
    assert readers.main(["--shared", str(shared_data.parent), "--repeats", "1", "--only", "HeadMR"]) == 0
    rows = [line for line in capsys.readouterr().out.splitlines() if line.startswith("| uniform/")]
    assert len(rows) == 1, rows
    cells = [c.strip() for c in rows[0].strip("|").split("|")]
    assert all(float(c) > 0 for c in cells[1:5]), cells  # three timings and their ratio
    assert cells[-2] == "0", cells  # the same values as VTK's reader
