"""The renderer registry with fake entry points: built-ins, plugins, broken and duplicate ones."""

from __future__ import annotations

import sys
import tomllib
import types
import warnings
from importlib import metadata
from pathlib import Path

import numpy as np
import pytest

from volren.errors import VolrenError, VolrenWarning
from volren.renderers.base import Capabilities, KindSupport, RendererBase
from volren.renderers.registry import BUILTIN_ENTRY_POINTS, ENTRY_POINT_GROUP, RendererRegistry, registry


class FakeRenderer(RendererBase):
    name = "fake"
    capabilities = Capabilities({"tet": KindSupport()}, backend="test")

    def _render(self, camera, width, height, progress):
        return np.zeros((height, width, 4), np.float32), {}


class Dist:
    def __init__(self, name):
        self.name = name


def ep(name, value, dist):
    entry = metadata.EntryPoint(name, value, ENTRY_POINT_GROUP)
    return entry._for(Dist(dist)) if hasattr(entry, "_for") else _with_dist(entry, dist)


def _with_dist(entry, dist):
    object.__setattr__(entry, "dist", Dist(dist))
    return entry


@pytest.fixture
def plugin_module(monkeypatch):
    module = types.ModuleType("fake_volren_plugin")
    module.FakeRenderer = FakeRenderer
    module.NotARenderer = object
    monkeypatch.setitem(sys.modules, "fake_volren_plugin", module)
    return module


def make_registry(*entries, fallback=False):
    return RendererRegistry(entry_points=lambda: list(entries), builtin_fallback=fallback)


def test_builtins_are_declared_in_pyproject_exactly_as_in_the_fallback_table():
    pyproject = tomllib.loads((Path(__file__).parents[2] / "pyproject.toml").read_text())
    assert pyproject["project"]["entry-points"][ENTRY_POINT_GROUP] == BUILTIN_ENTRY_POINTS


def test_installed_registry_lists_the_builtins():
    assert {"vtk", "reference"} <= set(registry.names())


def test_plugin_is_discovered_lazily(plugin_module):
    reg = make_registry(
        ep("vtk", BUILTIN_ENTRY_POINTS["vtk"], "volren"),
        ep("fake", "fake_volren_plugin:FakeRenderer", "volren-fake"),
    )
    assert reg.names() == ["vtk", "fake"]
    assert reg.get("fake") is FakeRenderer
    assert reg.capabilities("fake").volume_kinds == {"tet"}
    assert isinstance(reg.create("fake"), FakeRenderer)


def test_broken_plugin_is_reported_once_and_the_others_stay_usable(plugin_module):
    reg = make_registry(
        ep("fake", "fake_volren_plugin:FakeRenderer", "volren-fake"),
        ep("broken", "no_such_module_xyz:Renderer", "volren-broken"),
        ep("notarenderer", "fake_volren_plugin:NotARenderer", "volren-bad"),
    )
    with pytest.warns(VolrenWarning, match="broken.*ModuleNotFoundError") as record:
        with pytest.raises(VolrenError, match="unavailable"):
            reg.get("broken")
    assert len(record) == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no second warning
        with pytest.raises(VolrenError, match="unavailable"):
            reg.get("broken")
    with pytest.warns(VolrenWarning, match="lacks set_volume"):
        assert reg.available() == ["fake"]
    assert set(reg.failures) == {"broken", "notarenderer"}
    compat = reg.compatible("tet")
    assert compat["fake"] is None and "unavailable" in compat["broken"]


def test_duplicate_names_keep_the_builtin_then_the_first_plugin(plugin_module):
    with pytest.warns(VolrenWarning) as record:
        reg = make_registry(
            ep("vtk", "fake_volren_plugin:FakeRenderer", "aaa-shadow"),
            ep("vtk", BUILTIN_ENTRY_POINTS["vtk"], "volren"),
            ep("fake", "fake_volren_plugin:FakeRenderer", "zzz-second"),
            ep("fake", "fake_volren_plugin:Other", "bbb-first"),
        )
        names = reg.names()
    assert names == ["vtk", "fake"]
    messages = " | ".join(str(w.message) for w in record)
    assert "aaa-shadow" in messages and "zzz-second" in messages and len(record) == 2
    assert reg._discover()["vtk"].source == "volren"
    assert reg._discover()["fake"].source == "bbb-first"


def test_uninstalled_checkout_falls_back_to_the_builtin_table():
    assert RendererRegistry(entry_points=lambda: [])._discover() == {}  # volren is installed here
    reg = make_registry(fallback=True)
    assert set(reg.names()) == set(BUILTIN_ENTRY_POINTS)


def test_in_process_registration(plugin_module):
    reg = make_registry(ep("vtk", BUILTIN_ENTRY_POINTS["vtk"], "volren"))
    reg.register("fake", FakeRenderer)
    assert reg.get("fake") is FakeRenderer
    with pytest.raises(VolrenError, match="already registered"):
        reg.register("fake", FakeRenderer)
    with pytest.raises(VolrenError, match="built-in"):
        reg.register("vtk", FakeRenderer, replace=True)
    with pytest.raises(VolrenError, match="lacks"):
        reg.register("bad", object)
    reg.unregister("fake")
    with pytest.raises(VolrenError, match="unknown renderer 'fake'; registered: vtk"):
        reg.get("fake")


def test_capabilities_explain_what_is_unsupported():
    caps = Capabilities({"uniform": KindSupport(shading=True)})
    from volren.model.settings import RenderSettings

    assert caps.unsupported_reason("uniform") is None
    assert "tet" in caps.unsupported_reason("tet")
    assert "pre-integration" in caps.unsupported_reason("uniform", 1, RenderSettings(preintegration=True))
    assert "maximum" in caps.unsupported_reason("uniform", 1, RenderSettings(blend_mode="maximum"))
    assert "2D" in caps.unsupported_reason("uniform", 2)
