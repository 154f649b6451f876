"""The --raw-* flags: how a headerless raw INPUT is laid out, the same for every command that
reads one (`volren render`, `volren convert`).

They are needed where INPUT has no header (by their own names, with the cube its size suggests)
and refused where it has one, so that none is silently ignored.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from volren.errors import VolrenError

_DETAILS = ("--raw-dtype", "--raw-byte-order", "--raw-spacing")


def add_raw_arguments(parser: argparse.ArgumentParser) -> None:
    raw = parser.add_argument_group("headerless raw input")
    raw.add_argument("--raw-shape", help="NX,NY,NZ (needed for headerless raw data, and only for it)")
    raw.add_argument("--raw-dtype", help="sample type: uint8, int16, float32, ... or a C/NRRD/MetaImage name such as "
                                         "uchar, short, float (default uint8)")  # fmt: skip
    raw.add_argument("--raw-byte-order", choices=["little", "big"], help="default little")
    raw.add_argument("--raw-spacing", help="SX,SY,SZ (default 1,1,1)")


def _triple(text: str, what: str, kind=float) -> tuple:
    try:
        values = tuple(kind(v) for v in text.replace("x", ",").split(","))
    except ValueError:
        values = ()
    if len(values) != 3:
        raise VolrenError(f"{what} must be three comma-separated numbers, got {text!r}")
    return values


def raw_load_arguments(args: argparse.Namespace) -> dict[str, Any]:
    """`load_volume`'s arguments for the layout the flags give (none without --raw-shape)."""
    if not args.raw_shape:
        return {}
    return {
        "shape": _triple(args.raw_shape, "--raw-shape", int),
        "dtype": args.raw_dtype or "uint8",
        "byte_order": args.raw_byte_order or "little",
        "spacing": _triple(args.raw_spacing or "1,1,1", "--raw-spacing"),
    }


def check_raw_flags(args: argparse.Namespace, command: str) -> None:
    """Refuse raw flags that would be ignored, and a headerless INPUT without --raw-shape; `command`
    names the command in the message for flags given without an INPUT."""
    from volren.io.formats import find_format
    from volren.io.formats.raw import headerless_problem
    from volren.io.series_io import is_series

    given = [flag for flag in _DETAILS if getattr(args, flag[2:].replace("-", "_")) is not None]
    if args.raw_shape or args.input is None:
        if given and args.input is None:
            raise VolrenError(f"{given[0]} describes a headerless raw INPUT; this {command} has none")
        return
    path = Path(args.input)
    if is_series(path):
        if given:
            raise VolrenError(
                f"{path}: {given[0]} describes headerless raw data; a time series' steps have headers"
            )
        return
    if path.is_file() and path.stat().st_size and find_format(path) is None:
        raise VolrenError(f"{path}: {headerless_problem(path, flags=True)}")
    if given:
        raise VolrenError(f"{path}: {given[0]} describes headerless raw data only (it needs --raw-shape); "
                          f"this file's header says how it is laid out")  # fmt: skip
