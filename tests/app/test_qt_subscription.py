"""Widgets follow the state without the state keeping them alive, and nothing runs when they die."""

from __future__ import annotations

import gc

from PyQt5 import sip
from PyQt5.QtWidgets import QWidget

from volren.app.core.state import ViewState
from volren.app.qt_subscription import subscribe_while_alive


class Follower(QWidget):
    def __init__(self, state: ViewState) -> None:
        super().__init__()
        self.seen: list[str] = []
        subscribe_while_alive(state, self, "on_change")

    def on_change(self, change) -> None:
        self.seen.append(change.what)


def test_a_live_widget_follows_and_a_collected_one_is_dropped(qapp):
    state = ViewState()
    follower = Follower(state)
    state.set_background((0.1, 0.2, 0.3))
    assert follower.seen == ["background"]
    listeners = len(state._listeners)
    del follower
    gc.collect()
    state.set_background((0.3, 0.2, 0.1))  # the dead one's forwarder unsubscribes itself
    assert len(state._listeners) == listeners - 1


def test_a_widget_qt_deleted_is_not_called(qapp):
    state = ViewState()
    follower = Follower(state)
    seen = follower.seen
    sip.delete(follower)  # the C++ object is gone, the Python wrapper is still referenced here
    state.set_background((0.1, 0.2, 0.3))
    assert seen == []
