"""Tests choose which of raycast's 1D march kernels draws: numba's (`march`) or the C build's
(`march_native`), so that both are checked whichever the machine would pick."""

from __future__ import annotations

from types import ModuleType

import pytest

from volren.renderers.raycast import march as K
from volren.renderers.raycast import march_native

BACKENDS = ("numba", "c")


def use_backend(backend: str, monkeypatch: pytest.MonkeyPatch) -> ModuleType:
    """Make raycast's frames use `backend`'s kernels meanwhile; the module whose `march` and
    `march_pixels` they call. The C build is skipped where this machine cannot build it."""
    if backend == "numba":
        monkeypatch.setattr(march_native.numba_only, "on", True)
        return K
    if march_native._library() is None:
        pytest.skip("no C compiler here: the numba kernels draw")
    return march_native
