"""`auto` and the quality levels for multi-channel scenes (a TF per channel, mixed in one march):
only renderers whose capabilities say `channels` are chosen, and a level's pre-integration is
turned off for them (no renderer pre-integrates several channels)."""

from __future__ import annotations

import pytest

from volren import quality
from volren.errors import VolrenError
from volren.model import RenderSettings
from volren.model.scene_class import SceneClass
from volren.quality import NOT_AUTO, Measurement, QualityTable, channel_settings, choose_renderer
from volren.renderers.base import Capabilities, KindSupport, QualityLevel
from volren.renderers.registry import registry

UNIFORM = SceneClass("uniform")

#: Fake renderers, fastest first: `plain` mixes no channels, `mixes` does (post-classified only).
FAKES = {
    "plain": Capabilities({"uniform": KindSupport(preintegration=True, labels=True)}),
    "mixes": Capabilities({"uniform": KindSupport(preintegration=True, channels=True)}),
}
PRE_LEVEL = QualityLevel("pre", 0.5, True, {"table": 64})


@pytest.fixture
def fakes(monkeypatch):
    """The registry holding the fakes, each measured at every level with a pre-integrated
    configuration, plain the faster."""
    measured = {n: Measurement(PRE_LEVEL, {"a/smooth": ms}, {"a/smooth": 100.0}, 1.0) for n, ms in (("plain", 10),
                                                                                                   ("mixes", 20))}  # fmt: skip
    table = QualityTable({UNIFORM: {n: {lv: m for lv in quality.LEVELS} for n, m in measured.items()}}, {})
    monkeypatch.setattr(quality, "table", lambda: table)
    monkeypatch.setattr(registry, "names", lambda: list(FAKES))
    monkeypatch.setattr(registry, "capabilities", lambda name: FAKES[name])
    return table


def test_auto_takes_only_renderers_that_mix_channels(fakes):
    names = list(FAKES)
    assert choose_renderer(UNIFORM, "default", 1, RenderSettings(), names, fakes)[0] == "plain"
    # `mixes` has no pre-integration of channels, yet draws them with pre-integration off
    assert choose_renderer(UNIFORM, "default", 1, RenderSettings(), names, fakes, channels=True)[0] == "mixes"
    with pytest.raises(
        VolrenError, match=r"^no registered renderer can draw this uniform scene with channels "
    ):
        choose_renderer(UNIFORM, "default", 1, RenderSettings(), ["plain"], fakes, channels=True)


def test_resolve_applies_the_level_with_preintegration_off(fakes):
    name, settings, why = quality.resolve(UNIFORM, 1, "auto", "high", RenderSettings(), channels=True)
    assert (name, settings.step, settings.preintegration, dict(settings.options)) == ("mixes", 0.5, False,
                                                                                      {"table": 64})  # fmt: skip
    assert why is not None
    # a scene without channels keeps the level as measured
    assert quality.resolve(UNIFORM, 1, "mixes", "high", RenderSettings())[1].preintegration is True
    # no level: the caller's settings as they are (the renderer refuses what it cannot draw)
    own = RenderSettings(preintegration=True)
    assert quality.resolve(UNIFORM, 1, "mixes", None, own, channels=True)[1] == own


def test_channel_settings_changes_only_preintegration():
    on = RenderSettings(step=0.25, preintegration=True, shade=True, options={"x": 1})
    assert channel_settings(FAKES["mixes"], "uniform", on) == on.with_(preintegration=False)
    assert channel_settings(FAKES["plain"], "uniform", on) == on  # refused for its own reason instead
    assert channel_settings(FAKES["mixes"], "tet", on) == on
    off = on.with_(preintegration=False)
    assert channel_settings(FAKES["mixes"], "uniform", off) == off


def test_auto_with_the_registered_renderers_picks_one_that_mixes_channels():
    """Whatever the registry holds: `auto` picks a renderer whose capabilities mix channels, at its
    level's settings without pre-integration; where none outside NOT_AUTO does, the one-line error."""
    can = [n for n in registry.names()
           if n not in NOT_AUTO and (s := registry.capabilities(n).kinds.get("uniform")) and s.channels]  # fmt: skip
    if not can:
        with pytest.raises(
            VolrenError, match=r"^no registered renderer can draw this uniform scene with channels "
        ):
            quality.resolve(UNIFORM, 1, "auto", "default", RenderSettings(), channels=True)
        return
    name, settings, _ = quality.resolve(UNIFORM, 1, "auto", "default", RenderSettings(), channels=True)
    assert name in can and not settings.preintegration
    assert registry.capabilities(name).unsupported_reason("uniform", 1, settings, channels=True) is None
