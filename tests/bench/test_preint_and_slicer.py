"""`python -m benchmarks.preint` and `benchmarks.slicer_table` in process: the Markdown tables they
print (and write with --out) hold numeric timings and small errors, and bad arguments exit with
argparse's 2 or a one-line error."""

from __future__ import annotations

import math
import re

import pytest

from benchmarks import preint, slicer_table
from volren.samples import sample_paths

PREINT_ERROR = "python -m benchmarks.preint: error: "


def main(argv: list[str]) -> int:
    """The scripts' mains, called like `volren bench NAME ...` used to be."""
    assert argv[0] == "bench"
    return {"preint": preint.main, "slicer": slicer_table.main}[argv[1]](argv[2:])


@pytest.fixture(scope="module")
def sample_tf() -> str:
    return str(sample_paths("marschner_lobb")[1])


def small_run(tf: str, *extra: str) -> list[str]:
    return [
        "bench",
        "preint",
        "--tf",
        tf,
        "--sizes",
        "8,16",
        "--entries",
        "5",
        "--repeats",
        "1",
        "--lengths",
        "2",
        "--error-sizes",
        "8",
        *extra,
    ]


def rows(text: str, first_cell: str) -> list[list[str]]:
    """Cells of the Markdown rows whose first cell is `first_cell`."""
    out = []
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if line.startswith("|") and cells[0] == first_cell:
            out.append(cells)
    return out


def seconds(cell: str) -> float:
    """'1.23 ms' or '4.56 s' as seconds."""
    match = re.fullmatch(r"(\d+(?:\.\d+)?) (ms|s)", cell)
    assert match, f"not a timing: {cell!r}"
    return float(match[1]) * (1e-3 if match[2] == "ms" else 1.0)


def error(cell: str) -> float:
    """'2.3e-02' as a float."""
    assert re.fullmatch(r"\d\.\de[+-]\d\d", cell), f"not an error value: {cell!r}"
    return float(cell)


def test_preint_bench_prints_and_writes_both_tables(tmp_path, capsys, sample_tf):
    """The benchmark's output is what the docs quote: every cell must be a real measurement."""
    out = tmp_path / "t.md"
    assert main(small_run(sample_tf, "--oversampling", "2,4", "--out", str(out))) == 0
    text = capsys.readouterr().out
    assert out.read_text() == text

    header = next(line for line in text.splitlines() if line.startswith("| n |"))
    assert len(header.strip().strip("|").split("|")) == 12
    exact_errors = {}
    for n in ("8", "16"):
        (cells,) = rows(text, n)[:1]
        assert len(cells) == 12, cells
        # brute force, exact, approximate, 3D, lighting: all measured at these small sizes
        times = [seconds(c) for c in cells[1:6]]
        assert all(math.isfinite(t) and t > 0 for t in times), cells
        cached = re.fullmatch(r"(\d+\.\d{3}) ms", cells[6])
        assert cached and math.isfinite(float(cached[1])), cells[6]
        exact, approx, err3d, brute, exact_vs_brute = (error(c) for c in cells[7:12])
        assert all(0 <= e <= 1 for e in (exact, approx, err3d, brute)), cells
        # the O(n^2) table is the brute-force table, to float32 rounding
        assert exact_vs_brute <= 1e-6, cells
        assert math.isclose(exact, brute, rel_tol=0.06), cells  # same tables, 2-digit cells
        exact_errors[n] = exact
    # the error falls with n (as n_t^-2) and is small at n = 16
    assert exact_errors["16"] < exact_errors["8"] and exact_errors["16"] < 1e-2, exact_errors

    assert "| n \\ n_t | n_t = 2(n-1)+1 | n_t = 4(n-1)+1 |" in text
    (over,) = rows(text, "8")[1:]
    assert len(over) == 3
    by_factor = [error(c) for c in over[1:]]
    assert all(0 <= e < 1e-1 for e in by_factor) and by_factor[1] < by_factor[0], over


def test_oversampling_factor_one_is_accepted(capsys, sample_tf):
    """Factor 1 (n_t = n, no oversampling) is a valid column and in the default list (1, 2, 4, 8)."""
    code = main(small_run(sample_tf, "--sizes", "8", "--oversampling", "1,2"))
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert "n_t = 1(n-1)+1 | n_t = 2(n-1)+1" in captured.out


@pytest.mark.parametrize(
    "option, value",
    [("--sizes", "1"), ("--sizes", "a,b"), ("--sizes", ","), ("--error-sizes", "0"), ("--oversampling", "x")],
)
def test_bad_list_arguments_are_usage_errors(capsys, sample_tf, option, value):
    """Malformed lists are caught by argparse (exit 2, usage on stderr) before any work starts."""
    with pytest.raises(SystemExit) as exc:
        main(["bench", "preint", "--tf", sample_tf, option, value])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert f"argument {option}" in err and repr(value) in err


@pytest.mark.parametrize(
    "args, fragments",
    [
        (["--step", "0"], ["--step must be positive", "0"]),
        (["--step", "-1"], ["--step must be positive"]),
        (["--step", "nan"], ["--step must be positive"]),
        (["--lengths", "0"], ["--lengths must be positive"]),
        (["--entries", "0"], ["--entries must be positive"]),
        (["--repeats", "0"], ["--repeats must be positive"]),
        (["--tf", "{tmp}/missing.json"], ["missing.json", "no such file"]),
    ],
)
def test_bad_values_give_one_line_and_exit_1(tmp_path, capsys, sample_tf, args, fragments):
    """Mistakes a user can make are one `...: error:` line naming the problem, never a traceback."""
    argv = small_run(sample_tf) + [a.format(tmp=tmp_path) for a in args]
    assert main(argv) == 1
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(PREINT_ERROR), captured.err
    assert all(f in err[0] for f in fragments), err[0]
    assert captured.out == ""


def test_unwritable_out_file_is_an_error_after_printing(tmp_path, capsys, sample_tf):
    """The tables are still printed; the failed write is reported as a one-line error with status 1."""
    target = tmp_path / "no" / "such" / "dir" / "t.md"
    assert main(small_run(sample_tf, "--sizes", "8", "--oversampling", "2", "--out", str(target))) == 1
    captured = capsys.readouterr()
    assert rows(captured.out, "8") and not target.exists()
    last = captured.err.rstrip().split("\n")[-1].split("\r")[-1]  # after the cleared progress bar
    assert last.startswith(PREINT_ERROR) and str(target) in last and "cannot write" in last


@pytest.mark.usefixtures("renders_with_vtk")
def test_bench_slicer_prints_a_row_per_setting(shared_data, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("VOLREN_REFERENCE_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "table.md"
    code = main(
        [
            "bench",
            "slicer",
            "--shared",
            str(shared_data.parent),
            "--datasets",
            "bonsai",
            "--styles",
            "spiky",
            "--steps",
            "2",
            "--size",
            "16",
            "--frames",
            "1",
            "--out",
            str(out),
        ]
    )
    assert code == 0
    table = [r for r in rows(out.read_text(), "bonsai") if len(r) == 8]
    assert [r[2] for r in table] == ["slicer march post", "slicer march pre", "vtk"]
    for r in table:
        assert float(r[4]) > 0 and 0 <= float(r[5]) < 0.5  # ms per frame, RMSE
    printed = capsys.readouterr().out
    assert "slicer march pre" in printed and "time ratio" in printed
    assert len(rows(out.read_text(), "bonsai")) == 4  # three settings and one equal-error row


@pytest.mark.parametrize(
    "args, message",
    [
        (["--steps", "0"], "--steps"),
        (["--datasets", "spx"], "non-uniform"),
        (["--paths", "raycast"], "--paths"),
    ],
)
def test_bench_slicer_bad_arguments(shared_data, args, message, capsys):
    assert main(["bench", "slicer", "--shared", str(shared_data.parent), *args]) != 0
    assert message in capsys.readouterr().err
