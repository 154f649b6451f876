"""Reading and writing the small JSON files volren uses, with errors that name file and line.

ParaView writes presets with trailing commas (`[1, 2, ],`), which strict JSON refuses; they are
removed before parsing, keeping every newline so that line numbers in errors stay right.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

from volren.errors import file_error
from volren.io.safe_write import write_atomically

_TRAILING_COMMA = re.compile(r'("(?:[^"\\]|\\.)*")|,(\s*[\]}])', re.S)


def strip_trailing_commas(text: str) -> str:
    """Drop commas directly before ']' or '}' outside strings."""
    return _TRAILING_COMMA.sub(lambda m: m.group(1) or m.group(2), text)


def read_json(path: Path, lenient: bool = True) -> Any:
    """Parse a JSON file; any failure is a VolrenError naming the file (and the line)."""
    if not path.exists():
        raise file_error(path, "no such file")
    if path.is_dir():
        raise file_error(path, "is a folder, not a JSON file")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise file_error(path, f"not a text (UTF-8) file: {exc.reason} at byte {exc.start}") from None
    except OSError as exc:
        raise file_error(path, f"cannot read: {exc.strerror}") from None
    if not text.strip():
        raise file_error(path, "empty file")
    try:
        return json.loads(strip_trailing_commas(text) if lenient else text)
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
