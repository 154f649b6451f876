"""The toolbar's quality chooser: the measured settings of a `--quality` level (`volren.quality`)
for the renderer and volume shown, in one click.

Why in the toolbar beside the renderer: a level is a renderer's setting (the same name means a
different step, table or option for each renderer), so it is offered for the renderer in use,
with what was measured for it as the tooltip; levels with no measurements for that renderer and
kind are disabled. Choosing one replaces the step, pre-integration and renderer options and keeps
everything else (lighting, blend mode, crop); any later edit of those settings shows "custom".
"""

from __future__ import annotations

from PyQt5.QtWidgets import QComboBox, QWidget

from volren import quality
from volren.app.core.state import Change, ViewState
from volren.model.scene_class import SceneClass
from volren.quality import LEVELS, Measurement

#: The chooser's first entry: settings that are not exactly one level's.
CUSTOM = "custom"


def level_tooltip(level: str, choice: Measurement) -> str:
    return (f"{level}: {choice.level.label} (measured {choice.time_ratio(choice.ms):.2g}x VTK's default's frame "
            f"time, RMSE up to {choice.worst_error_ratio:.2g}x its RMSE, over {len(choice.ms)} scenes)")  # fmt: skip


class QualityControl:
    """Owns the quality combo box and keeps it in step with the state."""

    def __init__(self, state: ViewState, parent: QWidget) -> None:
        self._state = state
        self.chooser = QComboBox(parent)
        self.chooser.setObjectName("quality-chooser")
        self.chooser.addItems([CUSTOM, *LEVELS])
        self.chooser.setToolTip(
            "Settings measured for this renderer at each quality level (volren renderers)"
        )
        self.chooser.activated.connect(self._chosen)
        self._applying = False
        self.refresh()

    def _choice(self, level: str) -> Measurement | None:
        volume = self._state.volume
        if volume is None:
            return None
        kind = SceneClass.of(volume, self._state.transfer_function)
        return quality.table().measurement(
            self._state.renderer, kind, level
        )  # looked up now: tests swap the table

    def refresh(self) -> None:
        """Enable the levels measured for the renderer and volume shown; show which one the settings are."""
        model = self.chooser.model()
        for row, level in enumerate(LEVELS, start=1):
            choice = self._choice(level)
            item = model.item(row)
            item.setEnabled(choice is not None)
            item.setToolTip(level_tooltip(level, choice) if choice is not None else
                            f"no measurements of {self._state.renderer} at {level} on this kind of volume")  # fmt: skip
        self.chooser.setCurrentIndex(self.chooser.findText(self.shown_level() or CUSTOM))

    def shown_level(self) -> str | None:
        """The level the settings are: the one chosen when its settings are still the ones in use
        (levels can have equal settings), else the first that matches; None for custom settings."""
        state = self._state
        if state.volume is None:
            return None
        kind = SceneClass.of(state.volume, state.transfer_function)
        return quality.level_of(state.renderer, kind, state.settings, prefer=state.quality_level)

    def _chosen(self, index: int) -> None:
        level = self.chooser.itemText(index)
        choice = self._choice(level) if level != CUSTOM else None
        if choice is None:
            self.refresh()
            return
        self._applying = True
        try:
            self._state.quality_level = level
            self._state.set_settings(choice.level.replace(self._state.settings))
        finally:
            self._applying = False
        self.chooser.setCurrentIndex(index)

    def on_state_change(self, change: Change) -> None:
        if change.what in ("renderer", "volume", "settings") and not self._applying:
            self.refresh()
