"""Writing files so that no existing file is lost: to a temporary file beside the target, renamed
over it only once the write is complete; and refusing an output that is one of the inputs.

Why: a render whose `-o` names its own volume used to overwrite the volume with the PNG, and a
write that fails halfway (a full disk, a bad value) used to leave a truncated file in place of a
good one. A rename within one folder is atomic, so the target is either the old file or the new.
"""

from __future__ import annotations

import os
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


@contextmanager
def atomic_target(path: str | os.PathLike) -> Iterator[Path]:
    """A temporary path beside `path` to write to, renamed over `path` when the block ends
    normally; when it raises, the temporary file is removed and `path` is left as it was."""
    path = Path(path)
    fd, name = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=f".partial{_suffix(path)}", dir=path.parent)
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
                              inputs: Iterable[tuple[str, str | os.PathLike | None]], hint: str = "") -> None:
    """A one-line error when an output (flag, path) is one of the inputs (what, path) or when two
    outputs name one file. Paths are compared as files (links and relative paths resolved);
    `hint` ends the message (how to insist, where a command offers that)."""
    given_inputs = [(what, Path(p)) for what, p in inputs if p is not None]
    seen: list[tuple[str, Path]] = []
    for flag, text in outputs:
        if text is None:
            continue
        out = Path(text)
        for what, path in given_inputs:
            if path.is_file() and (_same(out, path) or out.resolve() == path.resolve()):
                raise VolrenError(f"{out}: {flag} would overwrite the {what}; choose another file{hint}")
        for other, path in seen:
            if out.resolve() == path.resolve():
                raise VolrenError(f"{out}: {flag} and {other} name the same file")
        seen.append((flag, out))
