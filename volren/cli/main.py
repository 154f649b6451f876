"""Entry point of the `volren` command: parses arguments, runs a subcommand, reports errors.

Errors people can cause print as one line ``volren: error: ...`` with exit status 1; usage
errors print one line naming the flag (no usage block) and exit with 2; anything unexpected prints
one line and exits with 3 unless ``--traceback`` asks for the full story. Warnings, log records and
stray VTK output print as one line each, once (`volren.cli.messages`).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import NoReturn

import volren
from volren.cli import (
    bench_cmd,
    check_cmd,
    convert_cmd,
    demo_cmd,
    movie_cmd,
    prepare_cmd,
    render_cmd,
    renderers_cmd,
    view_cmd,
)
from volren.cli.messages import one_line_messages
from volren.errors import VolrenError

COMMANDS = (renderers_cmd, render_cmd, movie_cmd, view_cmd, convert_cmd, demo_cmd, bench_cmd, check_cmd, prepare_cmd)


class OneLineParser(argparse.ArgumentParser):
    """argparse, with a usage error as one line that names the flag and where help is (the
    subcommands' parsers are made of the same class)."""

    def error(self, message: str) -> NoReturn:
        text = " ".join(message.split())
        self.exit(2, f"{self.prog}: error: {text} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog="volren", description="Volume rendering of uniform grids and tetrahedral meshes."
    )
    parser.add_argument("--version", action="version", version=f"volren {volren.__version__}")
    parser.add_argument("--traceback", action="store_true", help="show the full traceback on errors")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for command in COMMANDS:
        command.add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
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
