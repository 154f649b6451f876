"""Preview settings: the `interactive` level where the user's level is slower, the user's own
otherwise, plus the renderer's TF-drag options (no Qt)."""

import pytest

from volren import quality
from volren.app.core.preview_settings import preview_settings
from volren.model.scene_class import SceneClass
from volren.model.settings import RenderSettings
from volren.model.tf_class import TFClass
from volren.quality import Measurement, QualityTable
from volren.renderers.base import QualityLevel

UNIFORM = SceneClass("uniform")


def measured(
    label: str, step: float, pre: bool, options: dict, ms: dict, worst: float, meets: bool = True
) -> Measurement:
    """A measured level whose peer took 1 ms on every scene (ratios rank as frame times)."""
    return Measurement(QualityLevel(label, step, pre, options), ms, dict.fromkeys(ms, 1.0), worst, meets)


def _level(step: float, options: dict) -> Measurement:
    return measured(f"step {step}", step, False, options, {"a/smooth": 1.0}, 1.0)


@pytest.fixture
def levels(monkeypatch):
    table = QualityTable({SceneClass("uniform"): {"r": {"draft": _level(2.0, {"n": 16}), "interactive": _level(1.0, {"n": 64}),
                                            "default": _level(0.5, {"n": 256}), "exact": _level(0.1, {"n": 512})}}},
                         {})  # fmt: skip
    monkeypatch.setattr(quality, "table", lambda: table)
    return table


@pytest.mark.parametrize("level", ["default", "exact"])
def test_a_slower_level_previews_at_interactive(levels, level) -> None:
    settings = levels.measurement("r", UNIFORM, level).level.replace(RenderSettings(shade=True))
    preview = preview_settings("r", UNIFORM, settings)
    assert (preview.step, dict(preview.options), preview.shade) == (1.0, {"n": 64}, True)


@pytest.mark.parametrize("level", ["draft", "interactive"])
def test_a_level_as_fast_as_interactive_previews_as_it_is(levels, level) -> None:
    settings = levels.measurement("r", UNIFORM, level).level.replace(RenderSettings())
    assert preview_settings("r", UNIFORM, settings) == settings


def test_custom_settings_and_unmeasured_renderers_preview_as_they_are_plus_drag_options(levels) -> None:
    custom = RenderSettings(step=0.7, options={"n": 100})
    assert preview_settings("r", UNIFORM, custom) == custom
    assert preview_settings("other", UNIFORM, custom) == custom
    dragged = preview_settings("r", UNIFORM, custom, {"n": 8})
    assert (dragged.step, dict(dragged.options)) == (0.7, {"n": 8})
    default = levels.measurement("r", UNIFORM, "default").level.replace(RenderSettings())
    assert dict(preview_settings("r", UNIFORM, default, {"n": 8}).options) == {"n": 8}


def test_previews_go_to_the_fastest_renderer_measured_that_can_draw_the_scene(monkeypatch) -> None:
    from volren.app.core.preview_settings import preview_choice
    from volren.renderers.base import Capabilities, KindSupport

    table = QualityTable({SceneClass("uniform"): {
        "slow": {"interactive": _level(1.0, {"n": 64}), "default": _level(0.5, {"n": 256})},
        "fast": {"interactive": measured("fast", 1.0, False, {"m": 1}, {"a/smooth": 0.1}, 9.0, False)},
    }}, {})  # fmt: skip
    monkeypatch.setattr(quality, "table", lambda: table)
    shading = KindSupport(shading=True)
    caps = {"slow": Capabilities(kinds={"uniform": shading}),
            "fast": Capabilities(kinds={"uniform": KindSupport()}, tf_drag_options={"m": 2})}  # fmt: skip
    default = table.measurement("slow", UNIFORM, "default").level.replace(RenderSettings())
    names = ["slow", "fast", "unimportable"]
    renderer, settings = preview_choice("slow", UNIFORM, 1, default, names, caps.get, False)
    assert (renderer, settings.step, dict(settings.options)) == (
        "fast",
        1.0,
        {"m": 1},
    )  # worse error: still fastest
    # a scene kind with the TF's class: the kind's levels where the table has none for the class
    assert preview_choice(
        "slow", SceneClass("uniform", TFClass.SHARP), 1, default, names, caps.get, False
    ) == (renderer, settings)
    renderer, settings = preview_choice("slow", UNIFORM, 1, default, names, caps.get, True)
    assert (renderer, dict(settings.options)) == ("fast", {"m": 2})  # its own drag options
    shaded = default.with_(shade=True)  # fast cannot shade: the user's renderer previews
    renderer, settings = preview_choice("slow", UNIFORM, 1, shaded, names, caps.get, False)
    assert (renderer, settings.step, settings.shade) == ("slow", 1.0, True)
    custom = RenderSettings(step=0.7)
    assert preview_choice("slow", UNIFORM, 1, custom, names, caps.get, False) == ("slow", custom)


def test_reference_is_previewed_by_the_fastest_renderer_whatever_its_settings(monkeypatch) -> None:
    from volren.app.core.preview_settings import preview_choice
    from volren.renderers.base import Capabilities, KindSupport

    table = QualityTable({SceneClass("uniform"): {"fast": {"interactive": _level(1.0, {"m": 1})}}}, {})
    monkeypatch.setattr(quality, "table", lambda: table)
    caps = {
        "reference": Capabilities(kinds={"uniform": KindSupport()}),
        "fast": Capabilities(kinds={"uniform": KindSupport()}),
    }
    custom = RenderSettings(step=0.1)
    renderer, settings = preview_choice(
        "reference", UNIFORM, 1, custom, ["reference", "fast"], caps.get, False
    )
    assert (renderer, settings.step, dict(settings.options)) == ("fast", 1.0, {"m": 1})
