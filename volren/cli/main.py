"""Entry point of the `volren` command: parses arguments, runs a subcommand, reports errors.

Errors people can cause print as one line ``volren: error: ...`` with exit status 1; usage
errors print one line naming the flag (no usage block) and exit with 2; anything unexpected prints
one line and exits with 3 unless ``--traceback`` asks for the full story. Warnings, log records and
stray VTK output print as one line each, once (`volren.cli.messages`).
"""

from __future__ import annotations

import argparse
import gc
import importlib
import sys
from collections.abc import Sequence
from typing import NoReturn

import volren
from volren.cli.messages import one_line_messages
from volren.errors import VolrenError

#: The subcommands in `volren --help`'s order: (name, module in volren.cli, the line `--help` lists).
#: Only the module of the command run is imported: each imports what its command needs (numpy, the
#: model, the renderers, the bench's datasets), which a one-shot `volren render` should not pay for
#: the other commands. The lines are the ones each module's ``add_parser`` gives (a test holds them equal).
COMMANDS = (
    ("renderers", "renderers_cmd", "list registered renderers and their capabilities"),
    ("render", "render_cmd", "render a volume offscreen to a PNG"),
    ("movie", "movie_cmd", "render an orbit (or a scene's keyframes) offscreen to MP4 or GIF"),
    ("view", "view_cmd", "open the desktop app (a bundled sample when no INPUT)"),
    ("convert", "convert_cmd", "write a volume as a bricked multiresolution OME-Zarr image"),
    ("demo", "demo_cmd", "render the bundled samples with every renderer (offscreen)"),
    ("bench", "bench_cmd", "benchmarks (print tables of times and errors)"),
    ("check-renderer", "check_cmd", "run the conformance kit on a registered renderer"),
    ("prepare", "prepare_cmd", "compile the renderers' kernels now, so that first frames do not wait"),
)


class OneLineParser(argparse.ArgumentParser):
    """argparse, with a usage error as one line that names the flag and where help is (the
    subcommands' parsers are made of the same class)."""

    def error(self, message: str) -> NoReturn:
        text = " ".join(message.split())
        self.exit(2, f"{self.prog}: error: {text} (see {self.prog} --help)\n")


def build_parser(only: str | None = None, *, every: bool = True) -> argparse.ArgumentParser:
    """The parser with every subcommand's arguments, or (`every` False) with only those of the
    command `only` (the others listed by name and help line, their modules not imported)."""
    parser = OneLineParser(
        prog="volren", description="Volume rendering of uniform grids and tetrahedral meshes."
    )
    parser.add_argument("--version", action="version", version=f"volren {volren.__version__}")
    parser.add_argument("--traceback", action="store_true", help="show the full traceback on errors")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, module, help_line in COMMANDS:
        if every or name == only:
            importlib.import_module(f"volren.cli.{module}").add_parser(sub)
        else:
            sub.add_parser(name, help=help_line)
    return parser


def command_named(argv: Sequence[str]) -> str | None:
    """The subcommand `argv` runs: its first word that is not an option (`volren`'s own options
    take no values), or None."""
    return next((word for word in argv if not word.startswith("-")), None)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command in `argv` (default: the program's arguments) and return its exit status."""
    if argv is None:
        try:
            return _run(sys.argv[1:])
        finally:
            _leave_objects_to_the_os()
    return _run(list(argv))


def _leave_objects_to_the_os() -> None:
    """Exclude every object alive now from the interpreter's collections at exit. Tearing down what
    numba and VTK built took 0.3-0.45 s of a one-shot render's wall time on 2 cores (measured with
    `/usr/bin/time` against the same process ending after `gc.freeze`); the operating system frees
    the process's memory anyway, and atexit handlers still run. Only for the program itself: a caller
    of `main(argv)` keeps its collector."""
    gc.freeze()


def _run(argv: list[str]) -> int:
    parser = build_parser(command_named(argv), every=False)
    args = parser.parse_args(argv)
    try:
        with one_line_messages():
            return int(args.run(args) or 0)
    except VolrenError as exc:
        if args.traceback:
            raise
        print(f"volren: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("volren: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # never a traceback by default (DESIGN.md)
        if args.traceback:
            raise
        text = " ".join(str(exc).split())
        print(
            f"volren: internal error: {type(exc).__name__}: {text} (run with --traceback for details)",
            file=sys.stderr,
        )
        return 3


def entry_point() -> None:
    sys.exit(main())


if __name__ == "__main__":
    entry_point()
