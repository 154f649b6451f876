"""One fuzz case: the files it lays out, the `volren` command that reads them, what it should do.

A case is plain data (bytes and arguments), so the same corpus can be generated, run in forked
children or in fresh interpreters, and written out for a person to replay by hand.
"""

from __future__ import annotations

import os
import stat
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

Expect = Literal["render", "error", "any"]

#: Image size of every fuzz render: small, so that a case costs its reading, not its drawing.
SIZE = "24"

#: Values that header fields and flags should never take quietly (text form).
BAD_NUMBERS = (
    "0",
    "-1",
    "nan",
    "inf",
    "-inf",
    "1e308",
    "4294967296",
    "-2147483649",
    "99999999999999999999",
    "abc",
    "",
    "1,5",
)


@dataclass(frozen=True)
class Case:
    """A malformed (or valid) input and the `volren` arguments that use it.

    `files` are laid out in the case's own folder (paths relative to it); `argv` runs there.
    `expect` is what a correct volren does: "error" where any render would be accepting bad
    input silently, "render" for the valid seeds, "any" where either outcome can be right.
    `names` are the words an error message must contain one of (the files and flags at fault).
    `nodes` are what the case lays out besides files, after them: ("folder", path), ("fifo", path),
    ("socket", path), ("link", path, target) or ("read-only", folder). `after` is what must hold
    once the command ends, whatever it did: ("link", path) still a link, ("fifo", path) still a
    FIFO, ("kept", path) still the bytes laid out; and when it succeeded, ("written", path) a file
    or folder there (not the bytes laid out). `array` is the float32 RGBA array a success saves,
    checked and drawn twice (None: none is). `patches` are (module, attribute, value) set in a forked
    child before the command runs: a connection timeout made short, so that a case costs little.
    """

    name: str
    group: str
    files: dict[str, bytes]
    argv: tuple[str, ...]
    expect: Expect = "any"
    names: tuple[str, ...] = field(default=())
    nodes: tuple[tuple[str, ...], ...] = ()
    after: tuple[tuple[str, str], ...] = ()
    array: str | None = "out.npy"
    patches: tuple[tuple[str, str, float], ...] = ()

    def lay_out(self, folder: Path) -> None:
        """Write the case's files under `folder` (created), then make its other nodes."""
        folder.mkdir(parents=True, exist_ok=True)
        for rel, content in self.files.items():
            target = folder / rel
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(content)
        for kind, rel, *target in self.nodes:
            _make_node(folder / rel, kind, *target)

    def culprits(self) -> tuple[str, ...]:
        """What an error may name: the given names, else every file and every flag used."""
        if self.names:
            return self.names
        files = {Path(rel).parts[0] for rel in self.files}
        flags = {a.split("=")[0] for a in self.argv if a.startswith("--")}
        return tuple(sorted(files | flags))


def _make_node(path: Path, kind: str, target: str = "") -> None:
    """A folder, a FIFO, a socket, a symbolic link to `target` (relative to the link's folder), or a
    folder made read-only (its files too; whoever may write anyway, as root may, writes)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    if kind == "folder":
        path.mkdir(exist_ok=True)
    elif kind == "fifo":
        os.mkfifo(path)
    elif kind == "socket":
        os.mknod(path, 0o644 | stat.S_IFSOCK)  # a socket's file, with no socket behind it
    elif kind == "link":
        path.symlink_to(target)
    elif kind == "read-only":
        path.mkdir(exist_ok=True)
        path.chmod(0o555)
    else:
        raise ValueError(f"no such node kind: {kind}")


def render_argv(target: str, *extra: str) -> tuple[str, ...]:
    """`volren render TARGET` into out.png and out.npy at the fuzz size, plus `extra` flags."""
    return ("render", target, "-o", "out.png", "--save-array", "out.npy", "--size", SIZE, *extra)
