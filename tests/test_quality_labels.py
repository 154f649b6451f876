"""`auto` and the quality levels for label scenes (a label volume drawn with a TF per label):
only renderers whose capabilities say `labels` are chosen, and a level's pre-integration is
turned off for a renderer that draws labels without pre-integrating them."""

from __future__ import annotations

import pytest

from volren import quality
from volren.errors import VolrenError
from volren.model import RenderSettings
from volren.model.scene_class import SceneClass
from volren.quality import NOT_AUTO, Measurement, QualityTable, choose_renderer, label_settings
from volren.renderers.base import Capabilities, KindSupport, QualityLevel
from volren.renderers.registry import registry

UNIFORM = SceneClass("uniform")

#: Fake renderers, fastest first: `plain` draws no labels, `labels` draws them without
#: pre-integrating them, `preint` pre-integrates them too.
FAKES = {
    "plain": Capabilities({"uniform": KindSupport(preintegration=True)}),
    "labels": Capabilities({"uniform": KindSupport(preintegration=True, labels=True)}),
    "preint": Capabilities(
        {"uniform": KindSupport(preintegration=True, labels=True, labels_preintegration=True)}
    ),
}
PRE_LEVEL = QualityLevel("pre", 0.5, True, {"table": 64})


def measured(ms: float) -> Measurement:
    return Measurement(PRE_LEVEL, {"a/smooth": ms}, {"a/smooth": 100.0}, 1.0)


@pytest.fixture
def fakes(monkeypatch):
    """The registry holding the three fakes, each measured at every level with a pre-integrated
    configuration: plain the fastest, then labels, then preint."""
    table = QualityTable(
        {UNIFORM: {n: {lv: measured(ms) for lv in quality.LEVELS} for n, ms in zip(FAKES, (10, 20, 30))}}, {}
    )
    monkeypatch.setattr(quality, "table", lambda: table)
    monkeypatch.setattr(registry, "names", lambda: list(FAKES))
    monkeypatch.setattr(registry, "capabilities", lambda name: FAKES[name])
    return table


def test_auto_takes_only_renderers_that_draw_labels(fakes):
    names = list(FAKES)
    assert choose_renderer(UNIFORM, "default", 1, RenderSettings(), names, fakes)[0] == "plain"
    # `labels` cannot pre-integrate labels, yet it draws them with pre-integration off: the fastest that can
    assert choose_renderer(UNIFORM, "default", 1, RenderSettings(), names, fakes, labels=True)[0] == "labels"
    assert choose_renderer(UNIFORM, "default", 1, RenderSettings(), ["plain", "preint"], fakes, labels=True)[
        0
    ] == ("preint")
    with pytest.raises(
        VolrenError, match=r"^no registered renderer can draw this uniform scene with labels "
    ):
        choose_renderer(UNIFORM, "default", 1, RenderSettings(), ["plain"], fakes, labels=True)


def test_resolve_applies_the_level_with_preintegration_off_where_labels_are_not_preintegrated(fakes):
    name, settings, why = quality.resolve(UNIFORM, 1, "auto", "high", RenderSettings(), labels=True)
    assert (name, settings.step, settings.preintegration, dict(settings.options)) == ("labels", 0.5, False,
                                                                                      {"table": 64})  # fmt: skip
    assert why is not None
    # a renderer that pre-integrates labels keeps the level as measured; a scene without labels too
    assert (
        quality.resolve(UNIFORM, 1, "preint", "high", RenderSettings(), labels=True)[1].preintegration is True
    )
    assert quality.resolve(UNIFORM, 1, "labels", "high", RenderSettings())[1].preintegration is True
    # no level: the caller's settings as they are (the renderer refuses what it cannot draw)
    own = RenderSettings(preintegration=True)
    assert quality.resolve(UNIFORM, 1, "labels", None, own, labels=True)[1] == own


def test_label_settings_changes_only_preintegration():
    on = RenderSettings(step=0.25, preintegration=True, shade=True, options={"x": 1})
    assert label_settings(FAKES["labels"], "uniform", on) == on.with_(preintegration=False)
    assert label_settings(FAKES["preint"], "uniform", on) == on
    assert label_settings(FAKES["plain"], "uniform", on) == on  # refused for its own reason instead
    assert label_settings(FAKES["labels"], "tet", on) == on


def test_auto_with_the_registered_renderers_picks_one_that_says_labels():
    """Whatever the registry holds: `auto` picks a renderer whose capabilities draw labels (with
    its level's settings, pre-integration off where it does not pre-integrate labels), and where
    none outside NOT_AUTO does, the one-line error."""
    names = registry.names()
    can = [
        n
        for n in names
        if n not in NOT_AUTO and (s := registry.capabilities(n).kinds.get("uniform")) and s.labels
    ]
    if not can:
        with pytest.raises(
            VolrenError, match=r"^no registered renderer can draw this uniform scene with labels "
        ):
            quality.resolve(UNIFORM, 1, "auto", "default", RenderSettings(), labels=True)
        return
    name, settings, _ = quality.resolve(UNIFORM, 1, "auto", "default", RenderSettings(), labels=True)
    assert name in can
    capabilities = registry.capabilities(name)
    assert capabilities.unsupported_reason("uniform", 1, settings, labels=True) is None
    support = capabilities.kinds["uniform"]
    assert not settings.preintegration or support.labels_preintegration
