"""The progress callback of a long computation (a frame, a table, a file written): the model's, so
that kernels, readers and renderers all report through it without importing each other."""

from __future__ import annotations

from collections.abc import Callable

#: Called with the fraction done in [0, 1]; it may raise to cancel the frame.
ProgressCallback = Callable[[float], None]
