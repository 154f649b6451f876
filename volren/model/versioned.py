"""Change notification and version numbers for editable model objects (transfer functions).

Every edit takes a new `version` from one process-wide counter, so (version, ...) cache keys
(tables, textures) never collide, even across kinds of objects, and listeners (the app's
editors and viewport) hear of it.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from typing import Any

_versions = itertools.count(1)


class Versioned:
    """A `version` that changes on every edit, and `on_change` listeners called after it."""

    def __init__(self) -> None:
        self._listeners: list[Callable[[Any], None]] = []
        self.version = next(_versions)

    def on_change(self, callback: Callable[[Any], None]) -> Callable[[], None]:
        """Call `callback(obj)` after every edit; returns a function that disconnects it."""
        self._listeners.append(callback)
        return lambda: self._listeners.remove(callback)

    def _changed(self) -> None:
        self.version = next(_versions)
        for callback in list(self._listeners):
            callback(self)
