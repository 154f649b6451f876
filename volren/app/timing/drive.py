"""Driving the app's event loop as a person's input does, for measurements: the QApplication
(offscreen where there is no display), waiting in the loop until a condition holds, and a step
called at a mouse's 60 Hz."""

from __future__ import annotations

import time
from collections.abc import Callable

#: While waiting, the event loop wakes at least this often (ms) to test time-based conditions.
WAKE_MS = 2


def application():
    """The QApplication (offscreen where there is no display: the numbers do not need a screen)."""
    import os

    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    from volren.extras import require

    require("app", "volren bench app")
    from PyQt5.QtWidgets import QApplication

    return QApplication.instance() or QApplication(["volren"])


def wait(app, condition: Callable[[], bool], timeout_s: float) -> bool:
    """Run the event loop until `condition()` holds (False after `timeout_s`). It sleeps in the
    loop between events, as the app does: polling it every 0.5 ms took a third of a core from
    the renderer's two threads, which made TF-drag previews on oxygen 1.6x slower than alone."""
    from PyQt5.QtCore import QEventLoop, QTimer

    end = time.perf_counter() + timeout_s
    timer = QTimer()
    timer.start(WAKE_MS)
    try:
        while not condition():
            if time.perf_counter() > end:
                return False
            app.processEvents(QEventLoop.AllEvents | QEventLoop.WaitForMoreEvents)
    finally:
        timer.stop()
    return True


def drive_at_60hz(app, step: Callable[[int], None], seconds: float) -> float:
    """Call step(k) at 60 Hz (a mouse's event rate) for `seconds`, running the event loop between
    calls; returns the seconds it took."""
    start = time.perf_counter()
    k = 0
    while time.perf_counter() - start < seconds:
        step(k)
        k += 1
        wait(app, lambda k=k: time.perf_counter() - start >= k / 60.0, 1.0)
    return time.perf_counter() - start
