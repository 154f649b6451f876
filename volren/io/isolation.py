"""Reading a volume file in a child process, so that a reader that crashes takes only the child.

Why: VTK's readers are C++ that trusts its input. volren checks every header field it knows of
before a reader sees the file, but a file built to get past those checks can still crash a
reader, and a crash must not end the CLI without a word, nor take the app down with the user's
unsaved transfer function. So the whole load (header checks, the VTK reader, the conversion to a
model volume) runs in a child; the volume, or the one-line error, and the warnings come back
through a pipe; a child killed by a signal becomes one line naming the file.

How the child starts: `fork` where this process has a single thread, or only the threads numpy's
BLAS pool started at import (the CLI, scripts): it costs a few milliseconds and no imports. In a
process with other threads (the app, a notebook), a
forked child could inherit a lock that another thread held, so a `forkserver` started once (it
imports volren.io itself) forks the children instead. Without fork (Windows, macOS's default),
or with VOLREN_READ_IN_PROCESS=1, the load runs in this process.
"""

from __future__ import annotations

import mmap
import multiprocessing
import os
import pickle
import signal
import tempfile
import threading
import traceback
import warnings
from collections.abc import Callable
from multiprocessing.connection import Connection
from typing import Any

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


def _child(send: Connection, load: Callable[..., Any], args: tuple, kwargs: dict) -> None:
    """In the child: run the load, send ("ok", volume, warnings) or ("error", exception, warnings)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            outcome: tuple = ("ok", load(*args, **kwargs))
        except BaseException as exc:  # noqa: BLE001 - everything goes back to the parent
            if not isinstance(exc, VolrenError):  # what --traceback shows: the child's frames
                exc.add_note("".join(traceback.format_exception(exc)).rstrip())
            outcome = ("error", exc)
    notes = [(str(w.message), w.category.__name__) for w in caught]
    try:
        packed = _pack(outcome[1])
    except Exception as exc:  # noqa: BLE001 - an unpicklable exception or volume
        outcome, packed = ("error", None), _pack(RuntimeError(f"{type(exc).__name__}: {exc}"))
    send.send((outcome[0], packed, notes))
    send.close()


def _context() -> multiprocessing.context.BaseContext | None:
    if os.environ.get(_ENV_IN_PROCESS) == "1":
        return None
    methods = multiprocessing.get_all_start_methods()
    if "fork" not in methods:
        return None
    if _fork_is_safe():
        return multiprocessing.get_context("fork")
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(["volren.io"])
    return context


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
    context = _context()
    if context is None:
        return load(*args, **kwargs)
    receive, send = context.Pipe(duplex=False)
    child = context.Process(target=_child, args=(send, load, args, kwargs), daemon=True)
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
    status, packed, notes = message
    value = _unpack(*packed)
    for text, category in dict.fromkeys(notes):  # once each: the child recorded every repeat
        warnings.warn(text, VolrenWarning if category == "VolrenWarning" else RuntimeWarning, stacklevel=2)
    if status == "error":
        raise value from None
    return value
