"""Flags whose values can be checked alone are refused as usage errors naming them, before the
input is read (which can take minutes): --memory's size, --cluster's workers."""

from __future__ import annotations

import pytest

from volren.cli.main import main


@pytest.mark.parametrize("command", [["render", "v.vti", "-o", "x.png"], ["movie", "v.vti", "-o", "x.gif"],
                                     ["view", "v.vti"]])  # fmt: skip
@pytest.mark.parametrize(("size", "message"), [
    ("lots", "a memory size must look like 2GB, 512MB or 1.5GiB, got 'lots'"),
    ("0", "a memory size must be positive, got '0'"),
    ("nan", "a memory size must be positive, got 'nan'"),
])  # fmt: skip
def test_a_memory_size_that_is_no_size_is_a_usage_error_naming_memory(capsys, command, size, message):
    """The size was read only once the OME-Zarr image was open, in a message naming no flag."""
    with pytest.raises(SystemExit) as exc:
        main([*command, "--memory", size])
    prog = f"volren {command[0]}"
    assert exc.value.code == 2
    assert capsys.readouterr().err.splitlines() == [
        f"{prog}: error: argument --memory: {message} (see {prog} --help)"
    ]


def test_a_cluster_of_no_workers_is_refused_before_the_input_is_read(tmp_path, capsys):
    """--cluster local:0 was looked at only once the volume had been read: a missing or slow
    input was reported (or read) first."""
    argv = ["render", str(tmp_path / "nowhere.vti"), "-o", str(tmp_path / "x.png"), "--cluster", "local:0"]
    assert main(argv) == 1
    assert capsys.readouterr().err.splitlines() == [
        "volren: error: --cluster local:N needs N in 1..256 worker processes, got '0'"
    ]


@pytest.mark.parametrize(("command", "overhead", "copies"), [
    ("render", "about 370 MiB", "counts with the renderer's float copies"),
    ("convert", "about 170 MiB", "read whole (about 3x their values)"),
])  # fmt: skip
def test_memory_help_says_the_peak_is_the_fixed_overhead_plus_memory(capsys, command, overhead, copies):
    """The budget's rule, measured in docs/bricked.md: the help said only what --memory bounds, so
    a user who gave it their machine's free memory was over by the interpreter and libraries."""
    with pytest.raises(SystemExit):
        main([command, "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    memory = help_text[help_text.rindex("--memory SIZE") :]
    assert overhead in memory and copies in memory and "its peak is about that plus SIZE" in memory
