"""Undo and redo of transfer-function edits, recorded from the `ViewState` itself.

Editors do not push undo commands: every finished TF change (a click, a typed value, a file
opened, or a whole drag between `begin_interaction` and `end_interaction`) is noticed here by
comparing the TF's JSON form with the last one recorded. So each editor, present or future, gets
undo for free, a drag is one undo step, and an edit that changes nothing records nothing.
Undo puts a fresh TF object built from the JSON into the state (editors follow the state).
A new volume starts a new history: the old TFs belong to the old data range. With labels shown,
their styles (Real-Time Volume Graphics, chapter 16: a TF per label over the 1D TF) are part of
what is recorded, so the Labels panel's edits undo as TF edits do, and so are the labels' own TFs
(the 1D editor edits the selected label's). With channels mixed (Max 1995, section 2), what is
recorded is the whole TF per channel (every channel's TF, weight and visibility), so the Channels
panel's edits undo too, and selecting another channel to edit records nothing.
"""

from __future__ import annotations

import json
from typing import Any

from PyQt5.QtCore import QObject
from PyQt5.QtWidgets import QUndoCommand, QUndoStack

from volren.app.core.state import Change, ViewState
from volren.model.channels import ChannelTransferFunction
from volren.model.labels import LabelStyle
from volren.model.transfer_function_2d import transfer_function_from_dict

#: The snapshot's key of the label styles (`LabelTransferFunction.to_dict` without its base).
LABELS_KEY = "label_styles"


def _snapshot(state: ViewState) -> dict[str, Any] | None:
    channel_tf = state.channel_transfer_function
    if channel_tf is not None and state.channels_drawn:
        return channel_tf.to_dict()
    tf = state.base_transfer_function
    if tf is None:
        return None
    data = tf.to_dict()
    label_tf = state.label_transfer_function
    if label_tf is not None:
        labels = label_tf.to_dict()
        data[LABELS_KEY] = {"default": labels["default"], "labels": labels["labels"]}
    return data


class _TFChange(QUndoCommand):
    def __init__(self, history: TFHistory, before: dict[str, Any], after: dict[str, Any], label: str) -> None:
        super().__init__(label)
        self._history = history
        self._before = before
        self._after = after
        self._done = True  # pushed after the edit happened: the first redo() does nothing

    def redo(self) -> None:
        if self._done:
            self._done = False
            return
        self._history._apply(self._after)

    def undo(self) -> None:
        self._history._apply(self._before)


#: TF JSON keys as the editors name them (the JSON says "color", the editors "colour").
_UI_WORDS = {"color": "colour", LABELS_KEY: "labels"}


def _label(before: dict[str, Any] | None, after: dict[str, Any]) -> str:
    """The Edit menu's "Undo ..." text, in the editors' words."""
    if before is None or before.get("kind") != after.get("kind"):
        return "new transfer function"
    changed = sorted(k for k in after if before.get(k) != after.get(k))
    words = (_UI_WORDS.get(k, k.replace("_", " ")) for k in changed)
    return "edit " + (", ".join(words) if changed else "transfer function")


class TFHistory(QObject):
    """A QUndoStack of TF states; `stack.createUndoAction(...)` gives the menu actions."""

    def __init__(self, state: ViewState, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.state = state
        self.stack = QUndoStack(self)
        self._recorded = _snapshot(state)
        self._applying = False
        self._unsubscribe = state.subscribe(self._on_change)

    def _on_change(self, change: Change) -> None:
        if change.what == "volume" and not change.same_scene:  # a time step keeps the TF and its history
            self.stack.clear()
            self._recorded = _snapshot(self.state)
        elif change.what == "volume":  # labels opened or closed: not an edit to undo
            self._recorded = _snapshot(self.state)
        elif change.what in ("tf", "interaction") and not change.interactive and not self._applying:
            self.record()

    def record(self) -> None:
        """Push the TF as it is now, if it differs from the last recorded one."""
        now = _snapshot(self.state)
        if now is None or _same(now, self._recorded):
            return
        before, self._recorded = self._recorded, now
        if before is None:
            return
        self.stack.push(_TFChange(self, before, now, _label(before, now)))

    def _apply(self, data: dict[str, Any]) -> None:
        self._applying = True
        try:
            if data.get("kind") == "channels":
                self.state.set_channel_transfer_function(ChannelTransferFunction.from_dict(data))
                self._recorded = data
                return
            tf = {k: v for k, v in data.items() if k != LABELS_KEY}
            self.state.set_base_transfer_function(transfer_function_from_dict(tf))
            labels = data.get(LABELS_KEY)
            if labels is not None:
                styles = {int(k): LabelStyle.from_dict(v, f"label {k}") for k, v in labels["labels"].items()}
                self.state.set_label_styles(styles, LabelStyle.from_dict(labels["default"], "default"))
        finally:
            self._applying = False
        self._recorded = data

    def undo(self) -> None:
        self.stack.undo()

    def redo(self) -> None:
        self.stack.redo()

    def detach(self) -> None:
        self._unsubscribe()


def _same(a: dict[str, Any] | None, b: dict[str, Any] | None) -> bool:
    return json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)
