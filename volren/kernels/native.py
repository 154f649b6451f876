"""C kernels built on first use with the machine's C compiler and loaded with ctypes.

Why at run time and not at install: volren installs as pure Python (an editable install, or a wheel
with no compiler on the user's machine), and a kernel that cannot be built must leave the numba
kernel in charge, not fail the install. The library is cached per source, flags and compiler
(``$VOLREN_NATIVE_CACHE``, else ``$XDG_CACHE_HOME/volren/native``); `volren prepare` builds it
once at set-up, so a first frame does not wait for the compiler. A CPU with AVX2 and FMA gets the
source built with them (``__AVX2__`` defined), any other x86-64 or ARM CPU the portable build.
``VOLREN_NATIVE=0`` turns every C kernel off (the numba kernels draw the same image).
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import platform
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from functools import cache
from pathlib import Path

#: Flags of every build; the vector build adds `VECTOR_FLAGS`.
BASE_FLAGS = ("-O3", "-std=c11", "-fPIC", "-shared", "-pthread", "-fno-math-errno")
VECTOR_FLAGS = ("-mavx2", "-mfma")
#: Seconds a build may take before it is given up (the numba kernel then draws).
BUILD_TIMEOUT = 120


def enabled() -> bool:
    """False when ``VOLREN_NATIVE`` is 0, off or false: the numba kernels draw everything."""
    return os.environ.get("VOLREN_NATIVE", "1").strip().lower() not in ("0", "off", "false", "no")


def cache_dir() -> Path:
    """$VOLREN_NATIVE_CACHE, else $XDG_CACHE_HOME/volren/native (default ~/.cache/volren/native)."""
    if os.environ.get("VOLREN_NATIVE_CACHE"):
        return Path(os.environ["VOLREN_NATIVE_CACHE"])
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "volren" / "native"


def cpu_has_vector_units() -> bool:
    """Whether the CPU has AVX2 and FMA (Linux's /proc/cpuinfo; elsewhere, no)."""
    try:
        text = Path("/proc/cpuinfo").read_text(encoding="utf-8", errors="replace")
    except OSError:
        return False
    for line in text.splitlines():
        if line.startswith("flags"):
            flags = set(line.split(":", 1)[1].split())
            return {"avx2", "fma"} <= flags
    return False


def compiler() -> str | None:
    """The C compiler: $CC, else cc or gcc on the PATH; None where there is none."""
    return os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")


#: How many times `load` has handed out a library in this process (`volren prepare` asks whether a
#: renderer drew with C kernels).
_handed_out = [0]


def handed_out() -> int:
    """How many times `load` has returned a library in this process."""
    return _handed_out[0]


def load(source: Path) -> ctypes.CDLL | None:
    """The shared library built from the C file `source` for this CPU, built now unless cached;
    None where the C kernels are off, no compiler is found or the build fails."""
    lib = _load(source)
    if lib is not None:
        _handed_out[0] += 1
    return lib


@cache
def _load(source: Path) -> ctypes.CDLL | None:
    """`load`, once per source and process."""
    if not enabled():
        return None
    cc = compiler()
    if cc is None:
        return None
    flags = BASE_FLAGS + (VECTOR_FLAGS if cpu_has_vector_units() else ())
    code = source.read_bytes()
    digest = hashlib.sha256(b"\0".join([code, " ".join(flags).encode(), cc.encode(),
                                         platform.machine().encode()])).hexdigest()[:20]  # fmt: skip
    target = cache_dir() / f"{source.stem}-{digest}.so"
    if not target.is_file() and not _build(cc, flags, source, target):
        return None
    try:
        return ctypes.CDLL(str(target))
    except OSError:
        return None


def _drop_older(target: Path) -> None:
    """Remove the libraries built from earlier versions of the same source (best effort: a process
    that loaded one keeps its mapping)."""
    stem = target.name.rsplit("-", 1)[0]
    for old in target.parent.glob(f"{stem}-*.so"):
        if old != target and old.name.count("-") == target.name.count("-"):
            try:
                old.unlink()
            except OSError:
                pass


def _build(cc: str, flags: tuple[str, ...], source: Path, target: Path) -> bool:
    """Compile `source` into `target` through a temporary file in its folder, renamed into place
    (two processes building at once each leave a whole library); False where it fails."""
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(suffix=".so", dir=target.parent)
        os.close(fd)
    except OSError:
        return False
    try:
        done = subprocess.run([cc, *flags, "-o", tmp, str(source), "-lm"], capture_output=True,
                              timeout=BUILD_TIMEOUT, check=False)  # fmt: skip
        if done.returncode != 0:
            return False
        os.replace(tmp, target)
        _drop_older(target)
        return True
    except (OSError, subprocess.SubprocessError):
        return False
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def threads() -> int:
    """The threads a frame runs on: numba's count where numba is loaded (the app and the benchmarks
    set it), else $NUMBA_NUM_THREADS, else the cores this process may run on. numba is not imported
    for it: a frame a C kernel draws must not pay numba's import."""
    numba = sys.modules.get("numba")
    if numba is not None:
        return int(numba.get_num_threads())
    try:
        return max(1, int(os.environ["NUMBA_NUM_THREADS"]))
    except (KeyError, ValueError):
        pass
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


class NumbaOnly:
    """A switch that hands one C kernel's frames to the numba kernels it stands in for, meanwhile: benchmarks and tests
    compare the two (`with numba_only(): ...`; `numba_only.on` while inside)."""

    def __init__(self) -> None:
        self.on = False

    @contextmanager
    def __call__(self) -> Iterator[None]:
        before = self.on
        self.on = True
        try:
            yield
        finally:
            self.on = before
