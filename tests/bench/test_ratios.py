"""`python -m benchmarks.ratios`: a renderer against each peer setting at equal or lower error."""

from __future__ import annotations

import csv

from benchmarks import ratios

ROWS = [
    {"dataset": "d", "tf": "t", "renderer": "ours", "settings": "fast", "ms": "10", "rmse": "0.02"},
    {"dataset": "d", "tf": "t", "renderer": "ours", "settings": "fine", "ms": "40", "rmse": "0.005"},
    {"dataset": "d", "tf": "t", "renderer": "peer", "settings": "coarse", "ms": "50", "rmse": "0.03"},
    {"dataset": "d", "tf": "t", "renderer": "peer", "settings": "exact", "ms": "200", "rmse": "0.01"},
    {"dataset": "d", "tf": "t", "renderer": "peer", "settings": "beyond", "ms": "900", "rmse": "0.001"},
]


def write_runs(folder, rows):
    """A runs.csv of `rows` in `folder`, as `volren bench run` writes it (the columns ratios reads)."""
    path = folder / "runs.csv"
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(ROWS[0]))
        writer.writeheader()
        writer.writerows(rows)
    return path


def test_the_fastest_of_ours_at_or_below_each_peer_error():
    found = ratios.ratios(ROWS, "ours")[("d", "t", "peer")]
    # coarse: our fast setting (5x); exact: only the fine one reaches 0.01 (5x); beyond: none reaches
    assert sorted(found) == [(5.0, 50.0, "coarse", "fast"), (5.0, 200.0, "exact", "fine")]


def test_the_table(tmp_path, capsys):
    path = write_runs(tmp_path, ROWS)
    assert ratios.main([str(path), "ours"]) == 0
    out = capsys.readouterr().out
    assert "| d | t | peer | 5.00 (coarse: 50 ms; ours: fast) | 5.00-5.00 (2 settings) |" in out


def test_the_fragment_for_benchmarks_md(tmp_path):
    """`--fragment` writes the same table with the command that made it and a line per peer: the
    median and range of the ratios at the peer's fastest setting reached, over the scenes reached."""
    rows = ROWS + [
        {"dataset": "e", "tf": "t", "renderer": "ours", "settings": "fast", "ms": "10", "rmse": "0.02"},
        {"dataset": "e", "tf": "t", "renderer": "peer", "settings": "coarse", "ms": "20", "rmse": "0.05"},
        {"dataset": "f", "tf": "t", "renderer": "ours", "settings": "fast", "ms": "10", "rmse": "0.02"},
        {"dataset": "f", "tf": "t", "renderer": "peer", "settings": "exact", "ms": "500", "rmse": "0.001"},
    ]
    path = write_runs(tmp_path, rows)
    fragment = tmp_path / "peers.md"
    assert ratios.main([str(path), "ours", "--fragment", str(fragment)]) == 0
    text = fragment.read_text()
    assert f"`python -m benchmarks.ratios {path} ours --fragment {fragment}`" in text
    # d: 5.00 at the peer's fastest setting reached (coarse), e: 2.00; f is not reached
    assert (
        "- against `peer`: 2.00-5.00x at its fastest setting reached, on 2 of 3 scenes (median 3.50x)" in text
    )
    assert "| e | t | peer | 2.00 (coarse: 20 ms; ours: fast) | 2.00-2.00 (1 settings) |" in text
    assert "| f |" not in text


def test_an_unwritable_fragment_is_a_one_line_error(tmp_path, capsys):
    path = write_runs(tmp_path, ROWS)
    assert ratios.main([str(path), "ours", "--fragment", str(tmp_path / "missing" / "peers.md")]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and "peers.md: cannot write" in err and "\n" not in err
