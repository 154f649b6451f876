"""The `version` field of volren's JSON files: read it, and refuse files newer than this code."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from volren.errors import VolrenError


def check_format_version(data: Any, what: str, newest: int, default: int | None = None) -> int:
    """`data['version']` after checking `data` is an object and the version one we can read."""
    if not isinstance(data, Mapping):
        raise VolrenError(f"a {what} must be a JSON object, got {type(data).__name__}")
    version = data.get("version", default)
    if not isinstance(version, int) or isinstance(version, bool):
        raise VolrenError(f"{what} 'version' must be an integer, got {version!r}")
    if version < 1:
        raise VolrenError(f"{what} format version {version} does not exist: versions start at 1")
    if version > newest:
        raise VolrenError(
            f"{what} format version {version} is newer than this volren reads (up to {newest}); upgrade volren"
        )
    return version
