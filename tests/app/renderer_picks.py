"""Renderers for tests that need one lacking a feature: which ones lack it changes as renderers
gain features (vtk draws labels and channels now), so tests ask the registry instead of naming one."""

from __future__ import annotations

import pytest

from volren.renderers.registry import registry


def renderer_without(feature: str) -> str:
    """A registered renderer that draws uniform volumes with a 1D TF but not `feature` (a
    `KindSupport` flag: "labels", "channels"); the example plugin lacks both."""
    for name in registry.names():
        try:
            support = registry.capabilities(name).kinds.get("uniform")
        except Exception:  # noqa: BLE001 - a plugin that does not import is no candidate
            continue
        if support is not None and 1 in support.tf_dims and not getattr(support, feature):
            return name
    pytest.fail(f"no registered renderer draws uniform volumes without {feature}")
