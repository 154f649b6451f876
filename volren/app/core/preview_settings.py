"""What preview frames draw with: a cheaper renderer and settings than the still frame, chosen
from measurements; and what still frames draw with (`still_settings`).

Why: a preview (a frame while the mouse drags) must come within the frame budget at a useful
size; the still frame that follows has the user's quality. As in ParaView's and VTK's
level-of-detail rendering, previews of a scene at a measured quality level use the `interactive`
level's settings (`volren.quality`, measured by `volren bench run`) of the renderer measured
fastest at that level that can draw the scene (the fastest renderer for previews and
the chosen one for the still frame; the frame label says which drew it), and while a transfer
function is dragged, that renderer's `Capabilities.tf_drag_options` (options that make a new TF
cheap to apply, e.g. a smaller pre-integration table). Custom settings are previewed as they are,
by the user's renderer: the user chose them.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from typing import Any

from volren.model.scene_class import SceneClass
from volren.model.settings import RenderSettings
from volren.quality import LEVELS, NOT_AUTO, at_level, level_of, ranked
from volren.renderers.base import Capabilities

#: The level previews use when the user's level is slower.
PREVIEW_LEVEL = "interactive"


def preview_settings(renderer: str, kind: SceneClass, settings: RenderSettings,
                     tf_drag_options: Mapping[str, Any] | None = None) -> RenderSettings:  # fmt: skip
    """The settings of a preview frame of `renderer` on a scene of class `kind` whose still frames use
    `settings`; `tf_drag_options` are added while a TF is dragged."""
    level = level_of(renderer, kind, settings)
    if level is not None and LEVELS.index(level) > LEVELS.index(PREVIEW_LEVEL):
        settings = at_level(renderer, kind, PREVIEW_LEVEL, settings) or settings
    if tf_drag_options:
        settings = settings.with_(options={**settings.options, **tf_drag_options})
    return settings


def still_settings(settings: RenderSettings, capabilities: Capabilities | None) -> RenderSettings:
    """The settings a still frame (after a gesture, a screenshot, a movie) draws with: `settings`
    with the renderer's `still_frame_options` (image-space refinement off: every pixel sampled),
    so a still frame is never tiled whatever the level; previews keep the level's refinement."""
    extra = capabilities.still_frame_options if capabilities is not None else {}
    if all(settings.options.get(key, value) == value for key, value in extra.items()):
        return settings
    return settings.with_(options={**settings.options, **extra})


def preview_choice(renderer: str, kind: SceneClass, tf_dims: int, settings: RenderSettings, names: Iterable[str],
                   capabilities: Callable[[str], Capabilities | None], tf_dragged: bool) -> tuple[str, RenderSettings]:  # fmt: skip
    """(renderer, settings) of a preview frame of a scene whose still frames `renderer` draws with
    `settings`: the fastest renderer measured at the `interactive` level that can draw the scene
    (the user's own when it is the fastest, or when the settings are custom); `capabilities`
    gives a renderer's (None: it does not import). `reference` is previewed by the fastest renderer
    whatever its settings: its frames take seconds, and a drag showed nothing until release."""

    def drag(name: str) -> Mapping[str, Any] | None:
        caps = capabilities(name)
        return caps.tf_drag_options if tf_dragged and caps is not None else None

    if (
        level_of(renderer, kind, settings) is not None or renderer in NOT_AUTO
    ):  # reference: a frame takes seconds

        def can_draw(name: str) -> bool:
            caps = capabilities(name)
            at = at_level(name, kind, PREVIEW_LEVEL, settings)
            return (
                caps is not None
                and at is not None
                and caps.unsupported_reason(kind.kind, tf_dims, at) is None
            )

        fastest = next(
            (name for name in ranked(kind, PREVIEW_LEVEL, names, speed_only=True) if can_draw(name)), None
        )
        if fastest is not None and fastest != renderer:
            at = at_level(fastest, kind, PREVIEW_LEVEL, settings)
            assert at is not None
            return fastest, preview_settings(fastest, kind, at, drag(fastest))
    return renderer, preview_settings(renderer, kind, settings, drag(renderer))
