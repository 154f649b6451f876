"""Errors and warnings that volren shows to people.

Every failure a user can cause (a bad file, a bad option, a missing system library) is a
`VolrenError` whose message is one line naming the thing at fault and the problem, so the CLI can
print it as is and the app can show it in a message box.
"""

from __future__ import annotations

from pathlib import Path


class VolrenError(Exception):
    """A user-facing error with a one-line message."""

    def __init__(self, message: str) -> None:
        super().__init__(" ".join(str(message).split()))


class VolrenWarning(UserWarning):
    """Something was repaired or ignored; the work goes on (dropped cells, NaN values, ...)."""


def file_error(path: str | Path, problem: str) -> VolrenError:
    """The standard message for a file that cannot be used: '<path>: <problem>'."""
    return VolrenError(f"{path}: {problem}")
