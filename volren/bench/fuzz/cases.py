"""One fuzz case: the files it lays out, the `volren` command that reads them, what it should do.

A case is plain data (bytes and arguments), so the same corpus can be generated, run in forked
children or in fresh interpreters, and written out for a person to replay by hand.
"""

from __future__ import annotations

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
    """

    name: str
    group: str
    files: dict[str, bytes]
    argv: tuple[str, ...]
    expect: Expect = "any"
    names: tuple[str, ...] = field(default=())

    def lay_out(self, folder: Path) -> None:
        """Write the case's files under `folder` (created)."""
        folder.mkdir(parents=True, exist_ok=True)
        for rel, content in self.files.items():
            target = folder / rel
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(content)

    def culprits(self) -> tuple[str, ...]:
        """What an error may name: the given names, else every file and every flag used."""
        if self.names:
            return self.names
        files = {Path(rel).parts[0] for rel in self.files}
        flags = {a.split("=")[0] for a in self.argv if a.startswith("--")}
        return tuple(sorted(files | flags))


def render_argv(target: str, *extra: str) -> tuple[str, ...]:
    """`volren render TARGET` into out.png and out.npy at the fuzz size, plus `extra` flags."""
    return ("render", target, "-o", "out.png", "--save-array", "out.npy", "--size", SIZE, *extra)
