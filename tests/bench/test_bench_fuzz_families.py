"""The fuzz families of output paths, `convert`, `movie` and the cluster and memory flags: every case
written by hand is in the quick subset CI runs, cases lay out FIFOs, sockets and links, and the
runner sees what a command did to them (a FIFO or link replaced, an input changed, a success that
wrote nothing)."""

from __future__ import annotations

import os
import stat
import sys
from collections import Counter
from pathlib import Path

import pytest

from benchmarks import fuzz
from benchmarks.fuzz.cases import Case
from benchmarks.fuzz.command_cases import CONVERT, FLAGS, MOVIE, command_cases
from benchmarks.fuzz.output_cases import GROUP as OUTPUTS
from benchmarks.fuzz.output_cases import output_cases
from benchmarks.fuzz.runner import Run, classify_run, run_cases

#: The repository root, where `python -m benchmarks.fuzz` runs.
ROOT = Path(__file__).resolve().parents[2]

pytest.importorskip("zarr", reason="volren[zarr] is part of the test set-up")


def test_the_quick_subset_holds_every_case_written_by_hand_of_the_new_families():
    quick = {c.name for c in fuzz.quick_corpus()}
    cases = [*output_cases(), *command_cases()]
    by_hand = [c for c in cases if fuzz.written_by_hand(c)]
    assert {c.name for c in by_hand} <= quick
    assert {c.name for c in cases if "/sweep-" in c.name} - quick, "the sweeps run in full only"
    groups = Counter(c.group for c in by_hand)
    assert groups[OUTPUTS] >= 25 and groups[CONVERT] >= 40 and groups[MOVIE] >= 40 and groups[FLAGS] >= 30, (
        groups
    )
    for name in ("outputs/o=fifo", "outputs/save-array=link-to-file", "outputs/o=socket", "outputs/o=the-input",
                 "convert/valid", "convert/input-fifo", "convert/output-holds-the-input-force", "convert/raw-flags",
                 "movie/valid", "movie/fps=1e-300", "movie/fps=240", "movie/frames=0", "movie/o=fifo",
                 "cluster-memory-flags/cluster=local:0", "cluster-memory-flags/scheduler=tcp://127.0.0.1:9",
                 "cluster-memory-flags/memory=5XB", "cluster-memory-flags/v.vti--level=99"):  # fmt: skip
        assert name in quick, name


def test_a_case_lays_out_fifos_sockets_links_and_read_only_folders(tmp_path):
    case = Case("t/x", "t", {"real.png": b"old"}, ("render",), nodes=(
        ("fifo", "pipe"), ("socket", "sock"), ("folder", "dir"), ("link", "out.png", "real.png"),
        ("link", "dangling.png", "gone/x.png"), ("read-only", "locked")))  # fmt: skip
    case.lay_out(tmp_path)
    assert stat.S_ISFIFO((tmp_path / "pipe").lstat().st_mode) and stat.S_ISSOCK(
        (tmp_path / "sock").lstat().st_mode
    )
    assert (tmp_path / "dir").is_dir() and (tmp_path / "out.png").read_bytes() == b"old"
    assert os.readlink(tmp_path / "dangling.png") == "gone/x.png"
    assert stat.S_IMODE((tmp_path / "locked").stat().st_mode) == 0o555


def _case(**more) -> Case:
    return Case("t/x", "t", {"v.vti": b"volume"}, ("movie", "v.vti"), "any", ("v.vti",), **more)


def test_what_a_command_did_to_its_files_is_classified():
    """A success that saved no image is a render when the command saves none; a command that
    replaced what it must leave, or said it wrote what it did not, is bad output."""
    ok = Run(0, "movie: 2 frames -> out.gif\n", "", 0.1)
    assert classify_run(_case(array=None), ok)[0] == "render"
    assert classify_run(_case(), ok) == ("bad-pixels", "no image")
    replaced = Run(1, "", "volren: error: v.vti: bad\n", 0.1, bad_output="out.gif is no longer a FIFO")
    assert classify_run(_case(array=None), replaced) == ("bad-output", "out.gif is no longer a FIFO")


def test_the_runner_checks_the_files_after_each_command_and_applies_patches(tmp_path, monkeypatch):
    """Forked children: the command's effect on its files is seen from outside, and a case's
    patches are set in the child before the command runs."""
    import volren.cli.main as cli

    def fake_main(argv):
        what = argv[1]
        if what == "replace-fifo":
            Path("pipe").unlink()
            Path("pipe").write_bytes(b"a file now")
        if what == "replace-link":
            Path("out.gif").unlink()
            Path("out.gif").write_bytes(b"GIF89a")
        if what == "change-input":
            Path("v.vti").write_bytes(b"a PNG")
        if what == "write":
            Path("out.gif").write_bytes(b"GIF89a")
        if what == "patched":
            import volren.bricked.cluster as cluster

            print(f"volren: error: v.vti: waited {cluster.CONNECT_TIMEOUT_S:g} s", file=sys.stderr)
            return 1
        return 0

    monkeypatch.setattr(cli, "main", fake_main)
    after = (("fifo", "pipe"), ("link", "out.gif"), ("kept", "v.vti"), ("written", "real.gif"))
    nodes = (("fifo", "pipe"), ("link", "out.gif", "real.gif"))
    patch = (("volren.bricked.cluster", "CONNECT_TIMEOUT_S", 0.25),)
    cases = [
        Case(
            f"t/{w}",
            "t",
            {"v.vti": b"volume", "real.gif": b"old"},
            ("movie", w),
            "any",
            ("v.vti",),
            nodes,
            after,
            None,
            patch,
        )  # fmt: skip
        for w in ("replace-fifo", "replace-link", "change-input", "nothing", "write", "patched")
    ]
    results = run_cases(cases, tmp_path, jobs=2, timeout=20)
    assert [(r.outcome, r.detail) for r in results] == [
        ("bad-output", "pipe is no longer a FIFO"),
        ("bad-output", "out.gif is no longer a symbolic link"),
        ("bad-output", "v.vti was changed or removed"),
        ("bad-output", "real.gif was not written, yet the command succeeded"),
        ("render", ""),
        ("error", "volren: error: v.vti: waited 0.25 s"),
    ]


def test_every_convert_case_including_the_sweeps_finds_no_failures():
    """The convert family in full (the sweeps of bad --chunks and --levels run in full only), in a
    fresh process as `python -m benchmarks.fuzz` runs: huge --chunks and --levels were refused by the
    writer naming neither flag, and raw data given the --raw-* flags that convert now takes was
    still expected to be refused."""
    import subprocess

    done = subprocess.run([sys.executable, "-m", "benchmarks.fuzz", "--only", f"{CONVERT}/"],
                          cwd=ROOT, capture_output=True, text=True, timeout=300)  # fmt: skip
    summary = [line for line in done.stdout.splitlines() if " cases in " in line]
    assert summary and summary[-1].endswith(": 0 failures"), done.stdout[-3000:] + done.stderr[-2000:]
