"""The reading child (`volren.io.isolation`) where this process has threads: forked by a reader
server, a fresh interpreter that never runs the caller's script."""

from __future__ import annotations

import ctypes
import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

from volren.errors import VolrenError, VolrenWarning
from volren.io import isolation, load_volume
from volren.io.volume_io import read_with_header
from volren.samples import sample_paths


@pytest.fixture
def server_path(monkeypatch):
    """Loads go through a reader server of this test's own, stopped at the end."""
    monkeypatch.setattr(isolation, "_fork_is_safe", lambda: False)
    monkeypatch.setattr(isolation, "_idle", [])
    yield
    isolation._stop_servers()


def test_a_script_without_a_main_guard_runs_once_and_loads_twice(tmp_path):
    """The README's example as a plain script: the second load, after a thread started (as a
    render starts them), goes through a server (not a fork), which must not run the script again."""
    volume, _ = sample_paths("marschner_lobb")
    script = tmp_path / "example.py"
    script.write_text(
        textwrap.dedent(f"""\
        import threading, time
        from volren.io import load_volume

        with open("ran.txt", "a") as log:
            log.write("ran\\n")
        first = load_volume({str(volume)!r})
        threading.Thread(target=time.sleep, args=(30,), daemon=True).start()
        second = load_volume({str(volume)!r})
        print((first.values == second.values).all())
    """)
    )
    done = subprocess.run(
        [sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=120
    )
    assert (done.returncode, done.stdout.split(), done.stderr) == (0, ["True"], "")
    assert (tmp_path / "ran.txt").read_text() == "ran\n"


@pytest.mark.usefixtures("server_path")
def test_the_server_reads_and_reports_as_a_forked_child_does():
    volume, _ = sample_paths("marschner_lobb")
    read = load_volume(volume)
    assert np.array_equal(read.values, read_with_header(volume).values) and read.values.flags.writeable
    server = isolation._idle[0]
    with pytest.raises(VolrenError, match=r"^bad\.nrrd: the reader crashed \(SIGSEGV\) on this file"):
        isolation.run_isolated("bad.nrrd", _crash)
    with pytest.raises(VolrenError, match=r"^x\.vti: nothing here$"):
        isolation.run_isolated("x.vti", _fail, "x.vti")
    with pytest.warns(VolrenWarning, match="a note"):
        assert isolation.run_isolated("y", _warn_and_double, 21) == 42
    assert isolation._idle == [server] and server.process.poll() is None  # one server, past a crash


@pytest.mark.usefixtures("server_path")
@pytest.mark.parametrize("code, why", [
    ("import sys; sys.exit('volren is not installed here')", "volren is not installed here"),
    ("raise ImportError('No module named volren')", "No module named volren"),
    ("import os, signal; os.kill(os.getpid(), signal.SIGKILL)", "it crashed (SIGKILL)"),
])  # fmt: skip
def test_a_server_that_fails_to_start_is_one_line_that_does_not_blame_the_file(monkeypatch, code, why):
    monkeypatch.setattr(isolation, "_server_command", lambda: [sys.executable, "-c", code])
    with pytest.raises(VolrenError) as caught:
        isolation.run_isolated("good.vti", _fail, "good.vti")
    assert str(caught.value) == f"the reader process failed to start: {why}"
    assert isolation._idle == []


@pytest.mark.usefixtures("server_path")
def test_a_server_that_dies_during_a_load_is_one_line_and_the_next_load_starts_another():
    with pytest.raises(VolrenError, match=r"^the reader process stopped: "):
        isolation.run_isolated("good.vti", _kill_the_server)
    assert isolation._idle == []
    volume, _ = sample_paths("marschner_lobb")
    assert load_volume(volume).values.shape == (41, 41, 41)


def _kill_the_server() -> None:
    os.kill(os.getppid(), signal.SIGKILL)
    time.sleep(1)


def _crash() -> None:
    ctypes.string_at(0)


def _fail(path: str) -> None:
    raise VolrenError(f"{path}: nothing here")


def _warn_and_double(value: int) -> int:
    import warnings

    warnings.warn("a note", VolrenWarning, stacklevel=1)
    return 2 * value


@pytest.mark.usefixtures("server_path")
def test_the_server_reads_a_relative_path_in_the_callers_folder_and_environment(tmp_path, monkeypatch):
    """A server started in one folder serves a caller that moved to another since, and sees the
    environment the caller has now (a cache folder set after the server started)."""
    volume, _ = sample_paths("marschner_lobb")
    load_volume(volume)  # the server starts here, in this folder
    (tmp_path / "here.vti").write_bytes(open(volume, "rb").read())
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("VOLREN_ISOLATION_PROBE", "set after the server started")
    assert load_volume("here.vti").dimensions == load_volume(volume).dimensions
    assert (
        isolation.run_isolated("x", _environment, "VOLREN_ISOLATION_PROBE") == "set after the server started"
    )


def _environment(name: str) -> str | None:
    return os.environ.get(name)
