"""What the benchmark scripts' command lines share: list arguments and one-line errors
(`float_list` is `volren bench`'s own)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable

from volren.cli.bench_cmd import float_list
from volren.errors import VolrenError

__all__ = ["float_list", "int_list", "run"]


def int_list(minimum: int) -> Callable[[str], list[int]]:
    """argparse type: comma-separated whole numbers >= minimum."""

    def parse(text: str) -> list[int]:
        try:
            values = [int(v) for v in text.split(",") if v.strip()]
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"expected comma-separated whole numbers, got {text!r}"
            ) from None
        if not values or min(values) < minimum:
            raise argparse.ArgumentTypeError(f"expected whole numbers >= {minimum}, got {text!r}")
        return values

    return parse


def run(
    command: Callable[[argparse.Namespace], int], parser: argparse.ArgumentParser, argv: list[str] | None
) -> int:
    """Parse `argv` and run `command`; a `VolrenError` becomes one line on stderr and exit 1."""
    args = parser.parse_args(argv)
    try:
        return command(args)
    except VolrenError as exc:
        print(f"{parser.prog}: error: {exc}", file=sys.stderr)
        return 1
