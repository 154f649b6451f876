"""Output paths that are not a plain new file: a FIFO, a socket, a folder, links (to a file, to a
folder, to nothing, in a loop), a path under a file or in a missing folder, the input itself.

Each place (`spots`) is tried with `volren render -o` and `--save-array` here (the `outputs`
family), and with `volren movie -o` and `volren convert OUTPUT` in their own families. What was
there must survive a refusal (a FIFO stays a FIFO, a link a link, the input its bytes), nothing
non-regular may be opened (a FIFO opened by nobody would hang the command), and a link to a file
is written through, the link kept.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from benchmarks.fuzz.cases import Case, Expect
from benchmarks.fuzz.json_cases import _volume_files

GROUP = "outputs"
#: The valid input of every case in these families (a small uniform grid).
VOLUME = "v.vti"
#: Image side of these families' renders and movies.
SIDE = "16"


@dataclass(frozen=True)
class Spot:
    """A place an output flag is pointed at: what is laid out there, and what must hold after."""

    label: str
    path: str
    expect: Expect
    files: dict[str, bytes] = field(default_factory=dict)
    nodes: tuple[tuple[str, ...], ...] = ()
    after: tuple[tuple[str, str], ...] = ()


def spots(name: str) -> list[Spot]:
    """The places tried for an output normally called `name` (out.png, out.gif, out.zarr)."""
    real = f"real{Path(name).suffix}"
    return [
        Spot("fifo", name, "error", nodes=(("fifo", name),), after=(("fifo", name),)),
        Spot("socket", name, "error", nodes=(("socket", name),)),
        Spot("folder", name, "error", nodes=(("folder", name),)),
        Spot("link-to-file", name, "any", {real: b"old"}, (("link", name, real),), (("link", name), ("written", real))),
        Spot("link-to-folder", name, "error", nodes=(("folder", "dir"), ("link", name, "dir")),
             after=(("link", name),)),
        Spot("link-to-fifo", name, "error", nodes=(("fifo", "pipe"), ("link", name, "pipe")),
             after=(("link", name), ("fifo", "pipe"))),
        Spot("dangling-link", name, "any", nodes=(("link", name, real),), after=(("link", name), ("written", real))),
        Spot("link-into-missing-folder", name, "error", nodes=(("link", name, f"gone/{real}"),),
             after=(("link", name),)),
        Spot("link-loop", name, "error", nodes=(("link", name, name),)),
        Spot("under-a-file", f"file.txt/{name}", "error", {"file.txt": b"text"}, after=(("kept", "file.txt"),)),
        Spot("in-a-missing-folder", f"gone/{name}", "error"),
        Spot("the-input", VOLUME, "error", after=(("kept", VOLUME),)),
        # root writes in a read-only folder (and should: the permissions let it); anyone else is refused
        Spot("in-a-read-only-folder", f"locked/{name}", "any", nodes=(("read-only", "locked"),),
             after=(("written", f"locked/{name}"),)),
    ]  # fmt: skip


def spot_case(name: str, group: str, spot: Spot, argv: tuple[str, ...], flag: str, array: str | None,
              volume: dict[str, bytes]) -> Case:  # fmt: skip
    """The case of `argv` with `flag` pointed at `spot` (the input volume laid out beside it, and
    kept unless --force lets the output replace it)."""
    forced = "--force" in argv
    after = (
        tuple(a for a in spot.after if a != ("kept", VOLUME)) if forced else (*spot.after, ("kept", VOLUME))
    )
    expect = "any" if forced and spot.path == VOLUME else spot.expect
    return Case(
        name, group, {**volume, **spot.files}, argv, expect, (flag, spot.path), spot.nodes, after, array
    )


def render_argv(output: str = "out.png", array: str = "out.npy", *extra: str) -> tuple[str, ...]:
    return ("render", VOLUME, "-o", output, "--save-array", array, "--size", SIDE, *extra)


def output_cases() -> list[Case]:
    """`volren render -o` and `--save-array` at every place; the same again with --force (full
    run only: --force lets an output replace an input, and nothing else). The images are not
    checked (nor drawn twice): the volume is the valid seed, the places are what is tried."""
    volume = _volume_files()
    out = [Case(f"{GROUP}/valid", GROUP, volume, render_argv(), "render", after=(("written", "out.png"),))]
    for force in ((), ("--force",)):
        prefix = "sweep-force-" if force else ""
        for flag, name in (("-o", "out.png"), ("--save-array", "out.npy")):
            for spot in spots(name):
                paths = (spot.path, "out.npy") if flag == "-o" else ("out.png", spot.path)
                argv = render_argv(*paths, *force)
                out.append(spot_case(f"{GROUP}/{prefix}{flag.strip('-')}={spot.label}", GROUP, spot, argv, flag, None,
                                     volume))  # fmt: skip
    return out
