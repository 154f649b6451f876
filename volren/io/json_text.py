"""Reading and writing the small JSON files volren uses, with errors that name file and line.

ParaView writes presets with trailing commas (`[1, 2, ],`), which strict JSON refuses; they are
removed before parsing, keeping every newline so that line numbers in errors stay right.

JSON integers may have any number of digits, and Python reads them all; volren's numbers are
float64, and an integer beyond its range (1.8e308) failed every float conversion with an
exception of its own. Such an integer is read as infinity, as "1e400" is, which every check of a
number already refuses with its own message.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import numpy as np

from volren.errors import file_error
from volren.io.safe_write import write_atomically

#: Deepest nesting of arrays and objects read (TFs and scenes need 5; deeper is not one of ours,
#: and Python's parser would run out of stack on it).
MAX_DEPTH = 64
#: Largest JSON file read (a TF or scene is kilobytes; a TF at its point limit a few MB).
MAX_BYTES = 64 * 2**20
#: Integers of fewer digits lie within float64's range (1.8e308); longer ones are read as floats.
_INT_DIGITS = 300

_STRING = re.compile(r'"(?:[^"\\]|\\.)*"', re.S)
_TRAILING_COMMA = re.compile(r'("(?:[^"\\]|\\.)*")|,(\s*[\]}])', re.S)


def strip_trailing_commas(text: str) -> str:
    """Drop commas directly before ']' or '}' outside strings."""
    return _TRAILING_COMMA.sub(lambda m: m.group(1) or m.group(2), text)


def nesting_depth(text: str) -> int:
    """How deep arrays and objects nest in JSON text (strings skipped), in one linear pass."""
    brackets = _STRING.sub("", text).encode("utf-8", "replace")
    codes = np.frombuffer(brackets, np.uint8)
    steps = np.isin(codes, (ord("["), ord("{"))).astype(np.int64) - np.isin(codes, (ord("]"), ord("}")))
    return int(np.cumsum(steps).max(initial=0))


def _integer(text: str) -> int | float:
    """A JSON integer; a longer one as a float (beyond float64's range, the infinity of its sign)."""
    return int(text) if len(text.lstrip("-")) < _INT_DIGITS else float(text)


def read_json(path: Path, lenient: bool = True) -> Any:
    """Parse a JSON file; any failure is a VolrenError naming the file (and the line)."""
    if not path.exists():
        raise file_error(path, "no such file")
    if path.is_dir():
        raise file_error(path, "is a folder, not a JSON file")
    try:
        size = path.stat().st_size
    except OSError as exc:
        raise file_error(path, f"cannot read: {exc.strerror}") from None
    if size > MAX_BYTES:
        raise file_error(
            path,
            f"{size / 2**20:.0f} MiB is too large for a volren JSON file (at most {MAX_BYTES >> 20} MiB)",
        )
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise file_error(path, f"not a text (UTF-8) file: {exc.reason} at byte {exc.start}") from None
    except OSError as exc:
        raise file_error(path, f"cannot read: {exc.strerror}") from None
    if not text.strip():
        raise file_error(path, "empty file")
    depth = nesting_depth(text)
    if depth > MAX_DEPTH:
        raise file_error(path, f"arrays and objects nest {depth} deep; volren reads at most {MAX_DEPTH}")
    try:
        return json.loads(strip_trailing_commas(text) if lenient else text, parse_int=_integer)
    except json.JSONDecodeError as exc:
        raise file_error(path, f"invalid JSON at line {exc.lineno}, column {exc.colno}: {exc.msg}") from None


def write_json(data: Any, path: Path) -> None:
    """Write `data` as indented JSON (a VolrenError naming the file if that fails)."""
    try:
        text = json.dumps(data, indent=1, allow_nan=False) + "\n"
    except (TypeError, ValueError) as exc:
        raise file_error(path, f"cannot be written as JSON: {exc}") from None
    try:
        write_atomically(path, lambda tmp: tmp.write_text(text, encoding="utf-8"))
    except OSError as exc:
        raise file_error(path, f"cannot write: {exc.strerror}") from None
