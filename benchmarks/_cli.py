"""What the benchmark scripts' command lines share: list arguments and one-line errors."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable

from volren.errors import VolrenError


def int_list(minimum: int) -> Callable[[str], list[int]]:
    """argparse type: comma-separated whole numbers >= minimum."""

    def parse(text: str) -> list[int]:
        try:
            values = [int(v) for v in text.split(",") if v.strip()]
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected comma-separated whole numbers, got {text!r}") from None
        if not values or min(values) < minimum:
            raise argparse.ArgumentTypeError(f"expected whole numbers >= {minimum}, got {text!r}")
        return values

    return parse


def float_list(text: str, what: str) -> list[float]:
    """Comma-separated positive finite numbers, or a one-line error naming `what`."""
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise VolrenError(f"{what} must be comma-separated numbers, got {text!r}") from None
    if not values or not all(v > 0 and math.isfinite(v) for v in values):
        raise VolrenError(f"{what} must be positive finite numbers, got {text!r}")
    return values


def run(command: Callable[[argparse.Namespace], int], parser: argparse.ArgumentParser,
        argv: list[str] | None) -> int:
    """Parse `argv` and run `command`; a `VolrenError` becomes one line on stderr and exit 1."""
    args = parser.parse_args(argv)
    try:
        return command(args)
    except VolrenError as exc:
        print(f"{parser.prog}: error: {exc}", file=sys.stderr)
        return 1
