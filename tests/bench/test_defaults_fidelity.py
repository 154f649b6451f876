"""`python -m benchmarks.defaults_fidelity`: per scene and size, `auto` at `default` and VTK's
default against `reference`, with the count of pixels off beside RMSE."""

from __future__ import annotations

from benchmarks import defaults_fidelity


def _rows(text: str, prefix: str) -> list[list[str]]:
    return [
        [c.strip() for c in line.strip("|").split("|")]
        for line in text.splitlines()
        if line.startswith(prefix)
    ]


def test_a_row_per_size_with_both_errors_and_whether_it_holds(capsys, tmp_path, renders_with_vtk):
    out = tmp_path / "fidelity.md"
    argv = ["--datasets", "hard_specks", "--sizes", "24,40", "--out", str(out)]
    assert defaults_fidelity.main(argv) == 0
    rows = _rows(capsys.readouterr().out, "| hard_specks/hard |")
    assert [int(r[1]) for r in rows] == [24, 40]
    for row in rows:
        assert ":" in row[2]  # auto's choice, with its settings
        ours, vtk, ratio = (float(c) for c in row[3:6])
        ours_off, vtk_off = int(row[6]), int(row[7])
        assert abs(ratio - ours / vtk) <= 0.012 * ratio + 0.006  # RMSEs printed to 3 digits
        assert row[8] == ("yes" if ours <= vtk and ours_off <= vtk_off else "**no**")
    text = out.read_text()
    assert "--datasets hard_specks --sizes 24,40" in text and "rows hold" in text


def test_strict_fails_when_a_row_does_not_hold(monkeypatch, capsys, renders_with_vtk):
    real = defaults_fidelity.Row.holds
    monkeypatch.setattr(defaults_fidelity.Row, "holds", property(lambda self: False))
    assert defaults_fidelity.main(["--datasets", "hard_specks", "--sizes", "16", "--strict"]) == 1
    monkeypatch.setattr(defaults_fidelity.Row, "holds", real)
    assert "0 of 1 rows hold" in capsys.readouterr().out
