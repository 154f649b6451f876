"""The fuzz suite's OME-Zarr family: malformed metadata and chunks, the flags that choose how an
image is read, and a local server that fails; all in the quick subset CI runs, and all clean."""

from __future__ import annotations

import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest

from benchmarks import fuzz
from benchmarks.fuzz.runner import OUTCOMES
from benchmarks.fuzz.zarr_cases import HTTP_GROUP, written_by_hand, zarr_cases

#: The repository root, where `python -m benchmarks.fuzz` runs.
ROOT = Path(__file__).resolve().parents[2]

pytest.importorskip("zarr", reason="volren[zarr] is part of the test set-up")


def test_the_quick_subset_holds_every_ome_zarr_case_written_by_hand():
    quick = fuzz.quick_corpus()
    by_hand = [c for c in zarr_cases() if written_by_hand(c)]
    assert {c.name for c in by_hand} <= {c.name for c in quick}
    groups = Counter(c.group for c in by_hand)
    assert groups["ome-zarr"] >= 50 and groups[HTTP_GROUP] == 7
    names = {c.name for c in by_hand}
    for name in ("ome-zarr/zarray-chunks-zero", "ome-zarr/zattrs-transforms-as-strings", "ome-zarr/zattrs-range-short",
                 "ome-zarr/no-chunk-files", "ome-zarr/flag--memory=1", "ome-zarr/flag--cluster=empty",
                 "ome-zarr/flag--scheduler=tls://127.0.0.1:9", f"{HTTP_GROUP}/500", f"{HTTP_GROUP}/loop"):  # fmt: skip
        assert name in names, name


@pytest.mark.slow  # about 15 s
@pytest.mark.usefixtures("opengl")  # the slicer draws some cases, in subprocesses
def test_the_ome_zarr_cases_of_the_quick_subset_run_clean():
    """`python -m benchmarks.fuzz --quick --only ome-zarr` in a fresh process: every case an error naming the
    image or the flag, or a render, as it should be; not even a silent acceptance."""
    done = subprocess.run([sys.executable, "-m", "benchmarks.fuzz", "--quick", "--only", "ome-zarr"],
                          cwd=ROOT, capture_output=True, text=True, timeout=900)  # fmt: skip
    lines = done.stdout.splitlines()
    summary = [line for line in lines if " cases in " in line]
    assert summary and int(summary[-1].split()[0]) >= 60, done.stdout[-2000:] + done.stderr[-2000:]
    failures = [line for line in lines if line.split(":")[0] in OUTCOMES]
    assert not failures and done.returncode == 0, "\n".join(failures) + done.stderr[-2000:]
