"""Run fuzz cases as child processes with a time limit, and classify what came back.

Two ways to start a child: `fork` (default) forks this process after importing volren, VTK and
PyVista once and loading the ray caster's kernels (`preload`), so a case costs its own work (about
0.1 s for an error, not the 1 s of a fresh interpreter; a small grid's two renders 0.5 s, not 5 s);
`exec` runs `python -m volren.cli.main` afresh, exactly as a user would. Either way the child is
its own process: a crash, an abort or a hang is seen from outside.

A case's `patches` apply in a forked child only (a fresh interpreter runs as a user would).

A rendered case that saves an image runs twice with glibc's malloc perturbation set to two
different bytes (`mallopt(M_PERTURB)` in a forked child, `MALLOC_PERTURB_` in a fresh one): memory
a reader allocated and never filled then holds different bytes in the two runs, so an image drawn
from uninitialized memory differs between them instead of passing by luck.
"""

from __future__ import annotations

import ctypes
import faulthandler
import importlib
import logging
import os
import re
import resource
import select
import shutil
import signal
import stat
import subprocess
import sys
import time
import warnings
from collections.abc import Callable, Iterable, Iterator
from contextlib import ExitStack
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from benchmarks.fuzz.cases import Case

#: Outcome classes, worst first; a case's class is the worst of its runs.
FAILURES = (
    "crash",
    "hang",
    "traceback",
    "internal-error",
    "bad-output",
    "several-lines",
    "unnamed",
    "bad-pixels",
    "nondeterministic",
    "silent-accept",
    "reader-crash-isolated",
)
OUTCOMES = (*FAILURES, "error", "render", "render-warned")

_PERTURB = (0x5A, 0xC3)
_OURS = re.compile(r"^volren( [a-z-]+)?: (error|warning|interrupted)")
_M_PERTURB = -6  # glibc's mallopt parameter number
_HEAP_WORDS = ("double free", "corrupted", "malloc():", "free():", "munmap_chunk", "terminate called", "Segmentation fault", "Aborted")  # fmt: skip


@dataclass
class Run:
    """What one child did: exit status (negative: killed by that signal), output, time."""

    returncode: int
    stdout: str
    stderr: str
    seconds: float
    timed_out: bool = False
    image: np.ndarray | None = None
    bad_output: str = ""  # what the command did to its files that it must not (`Case.after`)


@dataclass
class Result:
    case: Case
    outcome: str
    detail: str
    runs: list[Run] = field(default_factory=list)

    @property
    def first_line(self) -> str:
        lines = (self.runs[0].stderr.strip() or self.runs[0].stdout.strip()).splitlines() if self.runs else []
        return lines[0][:300] if lines else ""


# ---------------------------------------------------------------------------------- children


def _child_main(
    case: Case, folder: Path, perturb: int, memory_limit: int
) -> None:  # pragma: no cover - child
    """In the forked child: redirect output, set the malloc perturbation and limits, run volren."""
    code = 3
    try:
        os.setpgid(0, 0)
        faulthandler.disable()  # a crash is the outcome, not something to report on the parent's stderr
        os.chdir(folder)
        for fd, name in ((1, "stdout.txt"), (2, "stderr.txt")):
            target = os.open(name, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
            os.dup2(target, fd)
            os.close(target)
        os.dup2(os.open(os.devnull, os.O_RDONLY), 0)
        sys.stdout = open(1, "w", closefd=False)  # noqa: SIM115 - the child's own streams on fds 1 and 2
        sys.stderr = open(2, "w", closefd=False)  # noqa: SIM115
        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
        if memory_limit:
            resource.setrlimit(resource.RLIMIT_AS, (memory_limit, memory_limit))
        ctypes.CDLL(None).mallopt(_M_PERTURB, perturb)
        logging.getLogger().handlers.clear()  # a fresh interpreter's logging: `benchmarks.fuzz` added its own
        warnings.resetwarnings()  # a fresh interpreter's filters, not the parent's (pytest's)
        for category in (DeprecationWarning, PendingDeprecationWarning, ImportWarning, ResourceWarning):
            warnings.simplefilter("ignore", category)
        from volren.cli.main import main

        for module, attribute, value in case.patches:
            setattr(importlib.import_module(module), attribute, value)
        try:
            code = int(main(list(case.argv)) or 0)
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
        except BaseException:
            import traceback

            traceback.print_exc()
            code = 1
    finally:
        try:
            sys.stdout.flush()
            sys.stderr.flush()
        finally:
            os._exit(code)


class _Child:
    """A started child: its pid, a descriptor that becomes readable when it ends, its deadline."""

    def __init__(self, pid: int, fd: int, deadline: float, proc: subprocess.Popen | None = None) -> None:
        self.pid, self.fd, self.deadline, self.proc = pid, fd, deadline, proc
        self.start = time.perf_counter()


def _start(case: Case, folder: Path, perturb: int, mode: str, timeout: float, memory_limit: int) -> _Child:
    deadline = time.perf_counter() + timeout
    if mode == "fork":
        sys.stdout.flush()
        sys.stderr.flush()
        pid = os.fork()
        if pid == 0:  # pragma: no cover - child
            _child_main(case, folder, perturb, memory_limit)
        return _Child(pid, os.pidfd_open(pid), deadline)
    env = {**os.environ, "MALLOC_PERTURB_": str(perturb)}
    with open(folder / "stdout.txt", "wb") as out, open(folder / "stderr.txt", "wb") as err:
        proc = subprocess.Popen(
            [sys.executable, "-m", "volren.cli.main", *case.argv],
            cwd=folder, stdout=out, stderr=err, stdin=subprocess.DEVNULL, env=env, start_new_session=True,
        )  # fmt: skip
    return _Child(proc.pid, os.pidfd_open(proc.pid), deadline, proc)


def _finish(case: Case, child: _Child, folder: Path, kill: bool) -> Run:
    if kill:
        try:
            os.killpg(child.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    _, status = os.waitpid(child.pid, 0)
    os.close(child.fd)
    code = os.waitstatus_to_exitcode(status)
    seconds = time.perf_counter() - child.start
    read = lambda name: (folder / name).read_bytes().decode("utf-8", "replace")  # noqa: E731
    image = None
    if code == 0 and case.array and (folder / case.array).is_file():
        try:
            image = np.load(folder / case.array, allow_pickle=False)
        except (ValueError, OSError):
            image = None
    return Run(
        code,
        read("stdout.txt"),
        read("stderr.txt"),
        seconds,
        kill,
        image,
        _bad_output(case, folder, code == 0),
    )


def _bad_output(case: Case, folder: Path, succeeded: bool) -> str:
    """The first of `case.after` that does not hold once the command ended, in words; "" if all do."""
    for check, rel in case.after:
        path = folder / rel
        if check == "link" and not path.is_symlink():
            return f"{rel} is no longer a symbolic link"
        if check == "fifo" and not (path.exists() and stat.S_ISFIFO(path.lstat().st_mode)):
            return f"{rel} is no longer a FIFO"
        if check == "kept" and not (path.is_file() and path.read_bytes() == case.files[rel]):
            return f"{rel} was changed or removed"
        if check == "written" and succeeded and not _written(path, case.files.get(rel)):
            return f"{rel} was not written, yet the command succeeded"
    return ""


def _written(path: Path, laid_out: bytes | None) -> bool:
    if path.is_dir():
        return any(path.iterdir())
    return path.is_file() and path.stat().st_size > 0 and path.read_bytes() != laid_out


# ---------------------------------------------------------------------------------- classifying


def _bad_pixels(image: np.ndarray | None) -> str:
    if image is None:
        return "no image"
    if image.ndim != 3 or image.shape[2] != 4 or image.dtype != np.float32:
        return f"image of shape {image.shape} {image.dtype}"
    if not np.isfinite(image).all():
        return "non-finite pixels"
    if image.min() < 0 or image.max() > 1:
        return f"pixels outside [0, 1] ({image.min():g}..{image.max():g})"
    if (image[..., :3] > image[..., 3:] + 1e-5).any():
        return "colour above alpha (not premultiplied)"
    return ""


def classify_run(case: Case, run: Run) -> tuple[str, str]:
    """The outcome of one run, and a detail for the report."""
    text = run.stdout + run.stderr
    if run.timed_out:
        return "hang", f"no answer in {run.seconds:.0f} s"
    if run.returncode < 0:
        return "crash", f"signal {signal.Signals(-run.returncode).name}"
    if any(w in text for w in _HEAP_WORDS):
        return "crash", next(w for w in _HEAP_WORDS if w in text)
    if "Traceback (most recent call last)" in text:
        return "traceback", text.strip().splitlines()[-1][:200]
    if run.returncode == 3 or "internal error" in run.stderr:
        return "internal-error", run.stderr.strip()[:200]
    if run.bad_output:
        return "bad-output", run.bad_output
    lines = [line for line in run.stderr.splitlines() if line.strip()]
    stray = [line for line in lines if not _OURS.match(line)]
    errors = [line for line in lines if _OURS.match(line) and ": error:" in line]
    out_lines = [line for line in run.stdout.splitlines() if line.strip()]
    if stray or len(errors) > 1 or len(out_lines) > 1:
        return "several-lines", (stray or errors[1:] or out_lines)[0][:200]
    if len(set(lines)) != len(lines):
        return "several-lines", "a warning printed more than once"
    if run.returncode != 0:
        if not errors:
            return "several-lines", f"exit {run.returncode} without an error line"
        message = errors[0]
        if "crashed" in message and "reader" in message:
            return "reader-crash-isolated", message[:200]
        if not any(name in message for name in case.culprits()):
            return "unnamed", message[:200]
        return "error", message[:200]
    problem = _bad_pixels(run.image) if case.array else ""
    if problem:
        return "bad-pixels", problem
    warned = any(": warning:" in line for line in lines)
    if case.expect == "error" and not warned:
        return "silent-accept", "rendered without a word"
    return ("render-warned" if warned else "render"), (lines[0][:200] if warned else "")


def classify(case: Case, runs: list[Run]) -> Result:
    outcomes = [classify_run(case, run) for run in runs]
    if len(runs) == 2 and all(o[0].startswith("render") for o in outcomes):
        a, b = runs[0].image, runs[1].image
        if a is not None and b is not None and (a.shape != b.shape or not np.array_equal(a, b)):
            diff = float(np.abs(a - b).max()) if a.shape == b.shape else float("inf")
            return Result(case, "nondeterministic", f"two runs differ by up to {diff:.3g}", runs)
    outcome, detail = min(outcomes, key=lambda o: OUTCOMES.index(o[0]))
    return Result(case, outcome, detail, runs)


# ---------------------------------------------------------------------------------- the loop


#: The CPU renderer that `volren render` chooses for the corpus's small grids (auto, at the default
#: quality), whose kernels the parent loads before forking (`preload`).
GRID_RENDERER = "raycast"


def preload() -> None:
    """Import what every case needs once, before forking (VTK, PyVista, the readers, the CLI), and
    load the numba kernels that `volren render` draws a small grid with, in both scalar types the ray
    caster keeps: a child then pays its own work only (a grid case took 2.5 s a run, most of it numba
    loading the cached kernels afresh in every child). The kernels run on numba's workqueue threads
    here and in the children: a child forked from a process whose GNU OpenMP threads have run aborts,
    while a workqueue child starts threads of its own. No OpenGL context is made before forking."""
    import numba

    try:
        layer = numba.threading_layer()  # this process has run a parallel kernel already
    except ValueError:
        numba.config.THREADING_LAYER = layer = "workqueue"
    import pyvista  # noqa: F401
    import vtkmodules.all  # noqa: F401

    import volren.api
    import volren.cli.main  # noqa: F401
    import volren.io  # noqa: F401
    from volren.model import UniformVolume

    if layer != "workqueue":  # loading the kernels would run them on threads no child may inherit
        return
    ramp = np.add.outer(np.add.outer(np.arange(6.0), np.arange(7.0)), np.arange(8.0))
    for dtype in (np.uint8, np.float32):
        volume = UniformVolume(ramp.astype(dtype), name="fuzz warm-up")
        volren.api.render(volume, renderer=GRID_RENDERER, size=(24, 24))


def run_cases(
    cases: Iterable[Case],
    work: Path,
    jobs: int = 2,
    timeout: float = 30.0,
    mode: str = "fork",
    memory_limit: int = 0,
    on_result: Callable[[Result], None] | None = None,
) -> list[Result]:
    """Run every case (twice when it renders), `jobs` children at a time; results in case order."""
    if mode == "fork":
        preload()
    with ExitStack() as stack:
        return _run_all(cases, work, jobs, timeout, mode, memory_limit, on_result, _Server(work, stack))


class _Server:
    """The local HTTP server of the cases that read over HTTP (`zarr_cases`), started by the first
    of them and serving `work`, the folder of every case's folder."""

    def __init__(self, work: Path, stack: ExitStack) -> None:
        self.work, self.stack, self.base = work, stack, ""

    def case_for(self, case: Case, folder: Path) -> Case:
        from benchmarks.fuzz.http_server import serving
        from benchmarks.fuzz.zarr_cases import needs_server, with_server

        if not needs_server(case):
            return case
        if not self.base:
            self.base = self.stack.enter_context(serving(self.work))
        return with_server(case, self.base, folder)


def _run_all(cases: Iterable[Case], work: Path, jobs: int, timeout: float, mode: str, memory_limit: int,
             on_result: Callable[[Result], None] | None, server: _Server) -> list[Result]:  # fmt: skip
    pending: Iterator[tuple[int, Case]] = iter(enumerate(cases))
    runs: dict[int, list[Run]] = {}
    results: dict[int, Result] = {}
    second: list[tuple[int, Case]] = []
    running: dict[int, tuple[int, Case, _Child, Path]] = {}
    exhausted = False

    def folder_for(index: int, case: Case, attempt: int) -> Path:
        folder = work / f"{index:05d}-{attempt}"
        shutil.rmtree(folder, ignore_errors=True)
        case.lay_out(folder)
        return folder

    while True:
        while len(running) < jobs and (second or not exhausted):
            if second:
                index, case = second.pop()
                attempt = 1
            else:
                nxt = next(pending, None)
                if nxt is None:
                    exhausted = True
                    continue
                index, case = nxt
                attempt = 0
            folder = folder_for(index, case, attempt)
            child = _start(
                server.case_for(case, folder), folder, _PERTURB[attempt], mode, timeout, memory_limit
            )
            running[child.fd] = (index, case, child, folder)
        if not running:
            break
        now = time.perf_counter()
        wait = max(0.0, min(c.deadline for _, _, c, _ in running.values()) - now)
        ready, _, _ = select.select(list(running), [], [], wait)
        now = time.perf_counter()
        for fd in list(running):
            index, case, child, folder = running[fd]
            late = now >= child.deadline
            if fd not in ready and not late:
                continue
            del running[fd]
            run = _finish(case, child, folder, kill=late and fd not in ready)
            runs.setdefault(index, []).append(run)
            first = classify_run(case, run)[0]
            if len(runs[index]) == 1 and first.startswith("render") and case.array:
                second.append((index, case))
                continue
            results[index] = classify(case, runs[index])
            shutil.rmtree(work / f"{index:05d}-0", ignore_errors=True)
            shutil.rmtree(work / f"{index:05d}-1", ignore_errors=True)
            if on_result:
                on_result(results[index])
    return [results[i] for i in sorted(results)]
