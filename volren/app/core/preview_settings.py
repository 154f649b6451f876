"""What preview frames draw with: cheaper settings than the still frame, chosen from measurements.

Why: a preview (a frame while the mouse drags) must come within the frame budget at a useful
size; the still frame that follows has the user's quality. As in ParaView's and VTK's
level-of-detail rendering, previews of a scene at a measured quality level use the `interactive`
level's settings for the same renderer (`volren.quality`, measured by `volren bench run`), and
while a transfer function is dragged, the renderer's `Capabilities.tf_drag_options` (options
that make a new TF cheap to apply, e.g. a smaller pre-integration table). Custom settings are
previewed as they are: the user chose them.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from volren.model.settings import RenderSettings
from volren.quality import LEVELS, at_level, level_of

#: The level previews use when the user's level is slower.
PREVIEW_LEVEL = "interactive"


def preview_settings(renderer: str, kind: str, settings: RenderSettings,
                     tf_drag_options: Mapping[str, Any] | None = None) -> RenderSettings:  # fmt: skip
    """The settings of a preview frame of `renderer` on a `kind` volume whose still frames use
    `settings`; `tf_drag_options` are added while a TF is dragged."""
    level = level_of(renderer, kind, settings)
    if level is not None and LEVELS.index(level) > LEVELS.index(PREVIEW_LEVEL):
        settings = at_level(renderer, kind, PREVIEW_LEVEL, settings) or settings
    if tf_drag_options:
        settings = settings.with_(options={**settings.options, **tf_drag_options})
    return settings
