"""Writing files so that no existing file is lost: to a temporary file beside the target, renamed
over it only once the write is complete; refusing an output that is one of the inputs, or that
holds one; and writing only where a file belongs.

Why: a render whose `-o` names its own volume used to overwrite the volume with the PNG, and a
write that fails halfway (a full disk, a bad value) used to leave a truncated file in place of a
good one. A rename within one folder is atomic, so the target is either the old file or the new.
A rename also replaces whatever has the target's name: a device (`-o /dev/full`, as root), a
FIFO or a symbolic link would have become a regular file. So an output that exists must be a
regular file (or, for an OME-Zarr folder, a folder), and a link is written through: its target
is replaced, the link stays.
"""

from __future__ import annotations

import os
import stat
import tempfile
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path

from volren.errors import VolrenError

#: The process's umask, read once (os.umask can only be read by setting it).
_UMASK = os.umask(0)
os.umask(_UMASK)


def _suffix(path: Path) -> str:
    """The suffix a writer may choose its format by (".vti", or ".nii.gz" for compressed ones)."""
    return "".join(path.suffixes[-2:]) if path.suffix == ".gz" else path.suffix


def _kind(path: Path) -> str | None:
    """What `path` (followed through links) is: "file", "folder", "FIFO", "socket", "device",
    None where nothing is there; an OSError where it cannot be looked at (a loop of links)."""
    try:
        mode = path.stat().st_mode
    except FileNotFoundError:
        return None
    if stat.S_ISREG(mode):
        return "file"
    if stat.S_ISDIR(mode):
        return "folder"
    if stat.S_ISFIFO(mode):
        return "FIFO"
    return "socket" if stat.S_ISSOCK(mode) else "device"


def output_target(path: str | os.PathLike, flag: str | None = None, kind: str = "file") -> Path:
    """Where output `path` is written: `path` itself, or the file a symbolic link points to (the
    link stays a link). A one-line error, naming `flag` where given, when something other than a
    `kind` ("file" or "folder", which may replace a file) has that name."""
    path = Path(path)
    target = Path(os.path.realpath(path))
    named = f"{flag} " if flag else ""
    try:
        found = _kind(target)
    except OSError as exc:
        raise VolrenError(f"{path}: {named}cannot be written: {exc.strerror}") from None
    if found not in (None, kind) and not (kind == "folder" and found == "file"):
        raise VolrenError(f"{path}: {named}must be a {kind}, not a {found}; choose another path")
    return target


def check_output(path: str | os.PathLike, flag: str | None = None, kind: str = "file") -> None:
    """Fail before a long render or load where the `kind` `path` cannot be written: something else
    has its name (`output_target`), its folder does not exist, or the folder takes no new file
    (tried with a temporary one: os.access says yes to root on a read-only mount)."""
    folder = output_target(path, flag, kind).parent
    if not folder.is_dir():
        raise VolrenError(f"{path}: the folder {folder} does not exist")
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as exc:
        raise VolrenError(f"{path}: cannot write in the folder {folder}: {exc.strerror}") from None


@contextmanager
def atomic_target(path: str | os.PathLike) -> Iterator[Path]:
    """A temporary path beside `path` to write to, renamed over `path` when the block ends
    normally; when it raises, the temporary file is removed and `path` is left as it was.
    `path` may be a link to a file (that file is replaced); it may not be anything but a file."""
    given, path = Path(path), output_target(path)
    fd, name = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=f".partial{_suffix(given)}", dir=path.parent)
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        mode = path.stat().st_mode & 0o7777 if path.exists() else 0o666 & ~_UMASK
        os.chmod(tmp, mode)  # mkstemp makes it private; the result gets the usual permissions
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_atomically(path: str | os.PathLike, write: Callable[[Path], None]) -> None:
    """Call write(temporary path) and rename the result over `path`; when `write` raises, the
    temporary file is removed, `path` is left as it was and the error propagates."""
    with atomic_target(path) as tmp:
        write(tmp)


def _same(a: Path, b: Path) -> bool:
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def refuse_overwriting_inputs(outputs: Iterable[tuple[str, str | os.PathLike | None]],
                              inputs: Iterable[tuple[str, str | os.PathLike | None]], hint: str = "",
                              kind: str = "file") -> None:  # fmt: skip
    """A one-line error when an output (flag, path) cannot be written as a `kind`
    (`output_target`), when it is one of the inputs (what, path) or a folder holding one, or when
    two outputs name one file. Paths are compared as files (links and relative paths resolved);
    `hint` ends the message (how to insist, where a command offers that)."""
    given_inputs = [(what, Path(p)) for what, p in inputs if p is not None]
    seen: list[tuple[str, Path]] = []
    for flag, text in outputs:
        if text is None:
            continue
        out = Path(text)
        output_target(out, flag, kind)
        for what, path in given_inputs:
            if not path.exists():
                continue
            if _same(out, path) or out.resolve() == path.resolve():
                raise VolrenError(f"{out}: {flag} would overwrite the {what}; choose another {kind}{hint}")
            if out.resolve() in path.resolve().parents:  # a folder, replaced whole
                raise VolrenError(f"{out}: {flag} holds the {what} {path}; replacing {flag} would delete it; "
                                  f"choose another {kind}{hint}")  # fmt: skip
        for other, path in seen:
            if out.resolve() == path.resolve():
                raise VolrenError(f"{out}: {flag} and {other} name the same file")
        seen.append((flag, out))
