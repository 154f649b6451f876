"""Reading a volume file in a child process, so that a reader that crashes takes only the child.

Why: VTK's readers are C++ that trusts its input. volren checks every header field it knows of
before a reader sees the file, but a file built to get past those checks can still crash a
reader, and a crash must not end the CLI without a word, nor take the app down with the user's
unsaved transfer function. So the whole load (header checks, the VTK reader, the conversion to a
model volume) runs in a child; the volume, or the one-line error, and the warnings come back
through a pipe; a child killed by a signal becomes one line naming the file.

How the child starts: `fork` where this process has a single thread, or only the threads numpy's
BLAS pool started at import (the CLI, scripts): it costs a few milliseconds and no imports. In a
process with other threads (the app, a notebook, a script after a render), a forked child could
inherit a lock that another thread held, so a reader server forks the children instead: a fresh
interpreter started once with `subprocess` (fork and exec, nothing run between them), which
imports volren.io and then forks a child a load (`_serve`). It never imports this process's
`__main__`, as multiprocessing's forkserver and spawn do: a script without an
`if __name__ == "__main__":` guard would run again in them. A server that dies before it said it
is ready is one line too, which does not blame the file. Without fork (Windows), or with
VOLREN_READ_IN_PROCESS=1, the load runs in this process.
"""

from __future__ import annotations

import atexit
import contextlib
import functools
import mmap
import multiprocessing
import os
import pickle
import re
import signal
import subprocess
import sys
import tempfile
import threading
import traceback
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from multiprocessing.connection import Connection
from typing import IO, Any

import numpy  # noqa: F401 - start its BLAS pool before _BASELINE is taken

from volren.errors import VolrenError, VolrenWarning, file_error

_ENV_IN_PROCESS = "VOLREN_READ_IN_PROCESS"
_SHM = "/dev/shm"


def _pack(value: Any) -> tuple[bytes, str | None, list[int]]:
    """`value` pickled, its large arrays' bytes out of band in one file in memory (/dev/shm):
    a pipe moves 16 MB in about 50 ms here, a file in memory in 5. Returns (pickle, the file or
    None, the buffers' sizes)."""
    buffers: list[pickle.PickleBuffer] = []
    data = pickle.dumps(value, protocol=5, buffer_callback=buffers.append)
    if not buffers:
        return data, None, []
    try:
        fd, name = tempfile.mkstemp(prefix="volren-", dir=_SHM if os.path.isdir(_SHM) else None)
        with os.fdopen(fd, "wb") as f:
            for buffer in buffers:
                f.write(buffer.raw())
    except OSError:  # no room: everything through the pipe
        return pickle.dumps(value, protocol=5), None, []
    return data, name, [b.raw().nbytes for b in buffers]


def _unpack(data: bytes, name: str | None, sizes: list[int]) -> Any:
    """The value `_pack` wrote. Its arrays map the file in memory copy-on-write (private): no
    copy is made, they stay writable, and the memory is freed with the last array."""
    if name is None:
        return pickle.loads(data)
    try:
        with open(name, "rb") as f:
            total = sum(sizes)
            whole = mmap.mmap(f.fileno(), total, flags=mmap.MAP_PRIVATE) if total else b""
    finally:
        os.unlink(name)
    view, buffers, start = memoryview(whole), [], 0
    for size in sizes:
        buffers.append(view[start : start + size])
        start += size
    return pickle.loads(data, buffers=buffers)


def _child(send: Callable[[tuple], None], work: Callable[[], Any]) -> None:
    """In the child: run the load, send ("ok", volume, warnings) or ("error", exception, warnings)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            outcome: tuple = ("ok", work())
        except BaseException as exc:  # noqa: BLE001 - everything goes back to the parent
            if not isinstance(exc, VolrenError):  # what --traceback shows: the child's frames
                exc.add_note("".join(traceback.format_exception(exc)).rstrip())
            outcome = ("error", exc)
    notes = [(str(w.message), w.category.__name__) for w in caught]
    try:
        packed = _pack(outcome[1])
    except Exception as exc:  # noqa: BLE001 - an unpicklable exception or volume
        outcome, packed = ("error", None), _pack(RuntimeError(f"{type(exc).__name__}: {exc}"))
    send((outcome[0], packed, notes))


def _forked_child(send: Connection, work: Callable[[], Any]) -> None:
    _child(send.send, work)
    send.close()


def _how_to_read() -> str:
    """ "here" (this process), "fork" or "server" (a fresh interpreter's fork): see the module's
    docstring."""
    if os.environ.get(_ENV_IN_PROCESS) == "1" or "fork" not in multiprocessing.get_all_start_methods():
        return "here"
    return "fork" if _fork_is_safe() else "server"


def _task_ids() -> frozenset[str] | None:
    """The ids of this process's threads, native ones included (OpenMP, numba and VTK pools that
    Python's `threading` does not see), or None where they cannot be listed."""
    try:
        return frozenset(os.listdir("/proc/self/task"))
    except OSError:
        return None


#: The threads this process had when this module was imported, if no Python thread ran then:
#: numpy's OpenBLAS pool, started on import (numpy is imported above). OpenBLAS quiesces it
#: around fork (pthread_atfork), so those threads do not make fork unsafe; threads started
#: later (GNU OpenMP, which kills a forked child that uses it, Qt, VTK) do.
_BASELINE = _task_ids() if threading.active_count() == 1 else None


def _fork_is_safe() -> bool:
    """Whether fork is safe here: one thread, or only the threads of the import-time baseline."""
    tasks = _task_ids()
    if tasks is None:  # threads cannot be counted: assume some, fork from a server
        return False
    if len(tasks) == 1:
        return True
    return _BASELINE is not None and threading.active_count() == 1 and tasks <= _BASELINE


def _signal_name(exitcode: int) -> str:
    try:
        return signal.Signals(-exitcode).name
    except ValueError:
        return f"signal {-exitcode}"


def run_isolated(path: object, load: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
    """`load(*args, **kwargs)` in a child process; its warnings re-issued here, its exception
    re-raised here, and a crash of the child a one-line VolrenError naming `path`."""
    how = _how_to_read()
    if how == "here":
        return load(*args, **kwargs)
    if how == "fork":
        message = _run_forked(path, functools.partial(load, *args, **kwargs))
    else:
        message = _run_in_server(
            path, pickle.dumps((load, args, kwargs, os.getcwd(), dict(os.environ)), protocol=5)
        )
    status, packed, notes = message
    value = _unpack(*packed)
    for text, category in dict.fromkeys(notes):  # once each: the child recorded every repeat
        warnings.warn(text, VolrenWarning if category == "VolrenWarning" else RuntimeWarning, stacklevel=2)
    if status == "error":
        raise value from None
    return value


def _run_forked(path: object, work: Callable[[], Any]) -> tuple:
    """The message of a child forked from this process to run `work`; a one-line VolrenError
    naming `path` where the child died first."""
    context = multiprocessing.get_context("fork")
    receive, send = context.Pipe(duplex=False)
    child = context.Process(target=_forked_child, args=(send, work), daemon=True)
    child.start()
    send.close()  # the child holds the only writer: its death is an end of file here
    try:
        try:
            message = receive.recv()
        except EOFError:
            message = None
        child.join()
    except BaseException:  # Ctrl+C or the app abandoning the load: the child must not linger
        child.kill()
        child.join()
        raise
    finally:
        receive.close()
    if message is None:
        code = child.exitcode or 0
        how = f"crashed ({_signal_name(code)})" if code < 0 else f"exited with status {code}"
        raise file_error(path, f"the reader {how} on this file: it is corrupt or not what its name says")
    return message


# ------------------------------------------------------------------------------ reader servers
#: What a server sends first, once its imports are done: a server that dies before it failed to
#: start, which is not the file's fault.
_READY = "ready"


def _serve() -> None:
    """A reader server's main, in a fresh interpreter: says it is ready, then for each request
    (the file's name, and the pickled load) forks a child that unpickles and runs the load, and
    answers with the child's message. The server unpickles nothing of the caller's: imports
    that start threads would make its forks unsafe."""
    answers = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)  # what a reader prints goes to stderr, not into the answers
    _send(answers, _READY)
    while True:
        try:
            path, request = pickle.load(sys.stdin.buffer)
        except EOFError:  # the caller has ended
            return
        try:
            message = _run_forked(path, functools.partial(_unpickled_call, request))
        except VolrenError as exc:  # the child crashed
            message = ("error", _pack(exc), [])
        _send(answers, message)


def _unpickled_call(request: bytes) -> Any:
    """The caller's load, in the caller's working folder and environment (the server was started
    in another's: a relative path or a cache variable set since must mean what it means there)."""
    load, args, kwargs, cwd, environ = pickle.loads(request)
    os.chdir(cwd)
    os.environ.clear()
    os.environ.update(environ)
    return load(*args, **kwargs)


def _send(stream: IO[bytes], message: object) -> None:
    pickle.dump(message, stream)
    stream.flush()


def _receive(stream: IO[bytes]) -> object | None:
    """The next message on `stream`, or None where its writer ended first."""
    try:
        return pickle.load(stream)
    except (EOFError, pickle.UnpicklingError):  # nothing, or a message cut short by a death
        return None


def _server_command() -> list[str]:
    """The interpreter running `_serve` with this process's sys.path: the server imports what
    this process would (volren.io among them, which its children need), and never this
    process's __main__."""
    code = f"import sys; sys.path[:] = {sys.path!r}; from volren.io.isolation import _serve; _serve()"
    return [sys.executable, "-c", code]


@dataclass
class _Server:
    """A running reader server: its pipes, its stderr (a file: a pipe could fill up and stop it),
    and whether it has said that it is ready."""

    process: subprocess.Popen
    errors: IO[bytes]
    ready: bool = False

    @classmethod
    def start(cls) -> _Server:
        errors = tempfile.TemporaryFile()
        try:  # a session of its own: Ctrl+C is this process's to handle, and ends the server with it
            process = subprocess.Popen(_server_command(), stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                       stderr=errors, start_new_session=True)  # fmt: skip
        except OSError as exc:  # no interpreter at sys.executable, no memory, no process left
            errors.close()
            raise VolrenError(f"the reader process failed to start: {exc.strerror or exc}") from None
        return cls(process, errors)

    def ask(self, path: object, request: bytes) -> tuple | None:
        """The message of the child that ran `request`, or None where the server died first."""
        try:
            _send(self.process.stdin, (str(path), request))  # type: ignore[arg-type]
        except BrokenPipeError:
            return None
        if not self.ready:
            self.ready = _receive(self.process.stdout) == _READY  # type: ignore[arg-type]
            if not self.ready:
                return None
        return _receive(self.process.stdout)  # type: ignore[arg-type,return-value]

    def death(self) -> VolrenError:
        """The server, which died, as one line: its last line on stderr (without an exception's
        class name), or how it ended."""
        self.errors.seek(0)
        last = self.errors.read().decode(errors="replace").strip().splitlines()[-1:]
        self.stop()
        code = self.process.returncode
        if last:
            why = re.sub(r"^[\w.]+(Error|Exception|Exit): ", "", last[0].strip())
        else:
            why = f"it crashed ({_signal_name(code)})" if code < 0 else f"it exited with status {code}"
        return VolrenError(f"the reader process {'stopped' if self.ready else 'failed to start'}: {why}")

    def stop(self) -> None:
        """End the server and the child it runs, if any (they share the server's session)."""
        with contextlib.suppress(ProcessLookupError):
            os.killpg(self.process.pid, signal.SIGKILL)
        self.process.wait()
        for stream in (self.process.stdin, self.process.stdout, self.errors):
            with contextlib.suppress(OSError):  # a pipe the server closed first
                stream.close()  # type: ignore[union-attr]


#: Servers waiting for a request: one, unless loads ran at once (the app reads in threads).
_idle: list[_Server] = []
_idle_lock = threading.Lock()


def _take_server() -> _Server:
    """An idle server that still runs, else a new one."""
    with _idle_lock:
        while _idle:
            server = _idle.pop()
            if server.process.poll() is None:
                return server
            server.stop()
    return _Server.start()


def _run_in_server(path: object, request: bytes) -> tuple:
    """The message of a child that a reader server forked to run `request`."""
    server = _take_server()
    try:
        message = server.ask(path, request)
    except BaseException:  # Ctrl+C or the app abandoning the load: the child must not linger
        server.stop()
        raise
    if message is None:
        raise server.death()
    with _idle_lock:
        _idle.append(server)
    return message


@atexit.register
def _stop_servers() -> None:
    with _idle_lock:
        while _idle:
            _idle.pop().stop()
