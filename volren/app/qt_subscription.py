"""Subscribing a widget to the `ViewState` for as long as the widget lives.

Why not `state.subscribe(self.method)` plus `self.destroyed.connect(unsubscribe)`: the bound
method keeps the widget's Python side alive, and PyQt can deliver `destroyed` while the garbage
collector is tearing that very widget down, which crashed the test process about one run in
four (a segfault in the `destroyed` lambda during `gc.collect()`). Here the state holds a plain
function with a weak reference: a widget that is gone, or whose C++ object Qt deleted, is
unsubscribed at the next change, and nothing runs at destruction.
"""

from __future__ import annotations

import weakref
from collections.abc import Callable

from PyQt5 import sip
from PyQt5.QtCore import QObject

from volren.app.core.state import Change, ViewState


def subscribe_while_alive(state: ViewState, widget: QObject, method: str) -> Callable[[], None]:
    """Call `widget.<method>(change)` after every change of `state` while `widget` lives;
    returns the function that unsubscribes."""
    ref = weakref.ref(widget)

    def forward(change: Change) -> None:
        target = ref()
        if target is None or sip.isdeleted(target):
            unsubscribe()
            return
        getattr(target, method)(change)

    unsubscribe = state.subscribe(forward)
    return unsubscribe
