"""The fuzz suite: its corpus is deterministic and covers every input kind, its runner sees
crashes, hangs and uninitialized images from outside, and the quick subset (what CI runs) finds
no crash, hang, traceback, internal error, several-line error, unnamed culprit or bad image."""

from __future__ import annotations

import ctypes
import os
import signal
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from benchmarks import fuzz
from benchmarks.fuzz.cases import Case
from benchmarks.fuzz.runner import FAILURES, Run, classify, classify_run, run_cases
from volren.errors import VolrenError
from volren.io.isolation import run_isolated

#: The repository root, where `python -m benchmarks.fuzz` runs.
ROOT = Path(__file__).resolve().parents[2]


def test_corpus_is_deterministic_and_covers_every_input():
    a, b = fuzz.corpus(), fuzz.corpus()
    assert len(a) >= 1000
    assert [c.name for c in a] == [c.name for c in b]
    assert all(x.files == y.files and x.argv == y.argv for x, y in zip(a, b))
    assert len({c.name for c in a}) == len(a), "case names are unique"
    groups = Counter(c.group for c in a)
    for group in ("vti", "vtu", "legacy", "nrrd", "nhdr", "mhd", "mha", "nii", "slc", "dicom", "raw", "mesh",
                  "tf1d", "tf2d", "scene", "flags"):  # fmt: skip
        assert groups[group] >= 10, group


def _case(expect="any") -> Case:
    return Case("t/x", "t", {"v.vti": b""}, ("render", "v.vti"), expect)


def _run(code=0, out="", err="", image=None, timed_out=False) -> Run:
    return Run(code, out, err, 0.1, timed_out, image)


def test_classification():
    ok = np.zeros((2, 2, 4), np.float32)
    assert classify_run(_case(), _run(-signal.SIGSEGV))[0] == "crash"
    assert (
        classify_run(_case(), _run(1, err="volren: error: v.vti: bad\nfree(): invalid pointer\n"))[0]
        == "crash"
    )
    assert classify_run(_case(), _run(0, timed_out=True))[0] == "hang"
    assert (
        classify_run(_case(), _run(1, err="Traceback (most recent call last):\n  x\nValueError: y\n"))[0]
        == "traceback"
    )
    assert (
        classify_run(_case(), _run(3, err="volren: internal error: ValueError: y\n"))[0] == "internal-error"
    )
    assert classify_run(_case(), _run(1, err="volren: error: v.vti: bad\nmore text\n"))[0] == "several-lines"
    assert classify_run(_case(), _run(1, err="volren: error: something is wrong\n"))[0] == "unnamed"
    assert classify_run(_case(), _run(1, err="volren: error: v.vti: truncated\n"))[0] == "error"
    bad = ok.copy()
    bad[0, 0] = (1, 0, 0, 0.5)
    assert classify_run(_case(), _run(0, "vtk: ok\n", image=bad))[0] == "bad-pixels"
    assert classify_run(_case(), _run(0, "vtk: ok\n", image=ok))[0] == "render"
    assert classify_run(_case("error"), _run(0, "vtk: ok\n", image=ok))[0] == "silent-accept"
    warned = _run(0, "vtk: ok\n", "volren: warning: v.vti: odd\n", image=ok)
    assert classify_run(_case("error"), warned)[0] == "render-warned"
    other = ok.copy()
    other[0, 0, 3] = 0.5
    result = classify(_case(), [_run(0, "vtk: ok\n", image=ok), _run(0, "vtk: ok\n", image=other)])
    assert result.outcome == "nondeterministic"


def test_runner_sees_crashes_and_hangs_from_outside(tmp_path, monkeypatch):
    """Forked children: a segfault, an abort and a hang in the code under test are classified,
    and this process goes on."""
    import volren.cli.main as cli

    def fake_main(argv):
        what = argv[1]
        if what == "segv":
            ctypes.string_at(0)
        if what == "abort":
            os.abort()
        if what == "hang":
            import time

            time.sleep(60)
        print("volren: error: fine: a clean error", file=__import__("sys").stderr)
        return 1

    monkeypatch.setattr(cli, "main", fake_main)
    cases = [
        Case(f"t/{w}", "t", {"a": b""}, ("render", w), "any", ("fine",))
        for w in ("segv", "abort", "hang", "fine")
    ]
    results = run_cases(cases, tmp_path, jobs=2, timeout=3)
    assert [r.outcome for r in results] == ["crash", "crash", "hang", "error"]


def _crash(path):
    ctypes.string_at(0)


def _fail(path):
    raise VolrenError(f"{path}: nothing here")


def test_a_crashing_reader_is_one_line_naming_the_file():
    with pytest.raises(VolrenError, match=r"^bad\.nrrd: the reader crashed \(SIGSEGV\) on this file"):
        run_isolated("bad.nrrd", _crash, "bad.nrrd")
    with pytest.raises(VolrenError, match=r"^x\.vti: nothing here$"):
        run_isolated("x.vti", _fail, "x.vti")
    values = np.arange(1_000_000, dtype=np.float32)
    back = run_isolated("big", np.copy, values)  # arrays come back whole, writable
    assert np.array_equal(back, values) and back.flags.writeable


@pytest.mark.slow  # about 40 s
@pytest.mark.usefixtures("renders_with_vtk")  # the corpus's scenes and flags, in subprocesses
def test_quick_corpus_finds_no_failures():
    """`python -m benchmarks.fuzz --quick` in a fresh process (forking this one, whose numba kernels have
    started OpenMP threads, would kill the children): no failure but silent acceptance, and none of
    that in the families written by hand (`fuzz.BY_HAND`)."""
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-m", "benchmarks.fuzz", "--quick"],
                          cwd=ROOT, capture_output=True, text=True, timeout=900)  # fmt: skip
    lines = done.stdout.splitlines()
    summary = [line for line in lines if " cases in " in line]
    assert summary and int(summary[-1].split()[0]) >= 300, done.stdout[-2000:] + done.stderr[-2000:]
    hard = [line for line in lines if line.split(":")[0] in FAILURES and not line.startswith("silent-accept")]
    assert not hard, "\n".join(hard)
    by_hand = [line for line in lines if line.startswith("silent-accept: ")
               and line.split(": ")[1].split("/")[0] in fuzz.BY_HAND]  # fmt: skip
    assert not by_hand, "\n".join(by_hand)
