"""`run()`: what `volren view` calls: make the window, open the input, run (or screenshot and exit).

With `screenshot`, the app is a headless check that the whole stack works: it waits for the first
full-quality frame of the loaded input, grabs the whole window, writes the PNG and exits 0; a load
or render error, or no frame within `timeout_s`, prints one line on stderr and exits 1. Without
a display it uses Qt's offscreen platform by itself, so it also runs on CI machines and servers.

Two process-level details matter for a PyQt app: an exception escaping a slot makes PyQt abort
the process unless `sys.excepthook` is replaced, so `run` installs a hook that reports one line
(the full traceback only with `traceback=True`) and keeps going; and Ctrl+C in the terminal quits
cleanly, which needs the interpreter to get control now and then during Qt's event loop.
"""

from __future__ import annotations

import os
import signal
import sys
import traceback as tb
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from volren.app.core.loading import PathArg, one_line_error

#: How long --screenshot waits for a full-quality frame (the reference renderer can be slow).
SCREENSHOT_TIMEOUT_S = 120.0
DEFAULT_WINDOW_SIZE = (1400, 800)


def _has_display() -> bool:
    if sys.platform != "linux" or os.environ.get("QT_QPA_PLATFORM"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def _error(message: str) -> int:
    print(f"volren: error: {message}", file=sys.stderr)
    return 1


@contextmanager
def _guarded(on_error: Callable[[str], None], full_traceback: bool) -> Iterator[None]:
    """Report exceptions from Qt callbacks in one line instead of letting PyQt abort."""
    previous = sys.excepthook

    def hook(exc_type, exc, trace) -> None:
        if issubclass(exc_type, KeyboardInterrupt):
            on_error("interrupted")
            return
        if full_traceback:
            tb.print_exception(exc_type, exc, trace)
        message = f"internal error: {one_line_error(exc)}"
        print(f"volren: {message}", file=sys.stderr)
        on_error(message)

    sys.excepthook = hook
    try:
        yield
    finally:
        sys.excepthook = previous


@contextmanager
def _quit_on_sigint(quit: Callable[[], None]) -> Iterator[None]:
    """Ctrl+C quits the event loop (the timer lets Python notice the signal while Qt runs)."""
    from PyQt5.QtCore import QTimer

    try:
        previous = signal.signal(signal.SIGINT, lambda *_: quit())
    except ValueError:  # not the main thread: leave signals alone
        yield
        return
    timer = QTimer()
    timer.timeout.connect(lambda: None)
    timer.start(250)
    try:
        yield
    finally:
        timer.stop()
        signal.signal(signal.SIGINT, previous)


#: Qt warnings that say nothing actionable (headless platforms, unset runtime dir).
QT_NOISE = ("propagateSizeHints", "XDG_RUNTIME_DIR", "QStandardPaths")


@contextmanager
def _quiet_qt() -> Iterator[None]:
    """Keep Qt's debug chatter and known-harmless warnings off stderr; errors stay one line."""
    from PyQt5.QtCore import QtCriticalMsg, QtFatalMsg, QtWarningMsg, qInstallMessageHandler

    def handler(kind, _context, message: str) -> None:
        if kind not in (QtWarningMsg, QtCriticalMsg, QtFatalMsg) or any(n in message for n in QT_NOISE):
            return
        print(f"volren: qt: {' '.join(message.split())}", file=sys.stderr)

    previous = qInstallMessageHandler(handler)
    try:
        yield
    finally:
        qInstallMessageHandler(previous)


def run(
    input: PathArg | None = None,
    tf: PathArg | None = None,
    scalars: str | None = None,
    renderer: str | None = None,
    screenshot: PathArg | None = None,
    *,
    memory: int | None = None,
    size: tuple[int, int] = DEFAULT_WINDOW_SIZE,
    timeout_s: float = SCREENSHOT_TIMEOUT_S,
    traceback: bool = False,
) -> int:
    """Open the app on `input` (default: the bundled sample); returns the exit status."""
    from volren.renderers.registry import registry

    if renderer is not None and renderer != "auto" and renderer not in registry.names():
        return _error(f"unknown renderer {renderer!r}; registered: {', '.join(registry.names())} (or auto)")
    if not _has_display():
        if screenshot is None:
            return _error("no display (DISPLAY is not set); run in a desktop session or under xvfb-run")
        os.environ["QT_QPA_PLATFORM"] = "offscreen"

    with _quiet_qt():
        return _run_app(input, tf, scalars, renderer, screenshot, size, timeout_s, traceback, memory)


def _run_app(input, tf, scalars, renderer, screenshot, size, timeout_s: float, traceback: bool,
             memory: int | None = None) -> int:  # fmt: skip
    from PyQt5.QtWidgets import QApplication

    from volren.app.window.main_window import MainWindow

    app = QApplication.instance() or QApplication([sys.argv[0] if sys.argv else "volren"])
    app.setApplicationName("volren")
    window = MainWindow()
    window.resize(*size)
    if memory is not None:
        window.files.zarr_memory = memory
    if screenshot is not None:
        return _screenshot(window, input, tf, scalars, renderer, Path(screenshot), timeout_s, traceback)
    status = {"code": 0}

    def on_problem(message: str) -> None:
        if message == "interrupted":
            status["code"] = 130
            app.quit()
        else:  # an internal error was printed; the app goes on
            window.statusBar().showMessage(message, 15000)

    with _guarded(on_problem, traceback), _quit_on_sigint(lambda: on_problem("interrupted")):
        window.show()
        window.files.open_input(input, tf, scalars, renderer)
        try:
            code = int(app.exec_())
        finally:
            window.shutdown()
    return status["code"] or code


def _screenshot(window, input, tf, scalars, renderer, path: Path, timeout_s: float, traceback: bool) -> int:
    from PyQt5.QtCore import QEventLoop, QTimer
    from PyQt5.QtWidgets import QApplication

    loop = QEventLoop()
    outcome: dict[str, object] = {}

    def finish(status: int, message: str = "") -> None:
        if not outcome:
            outcome.update(status=status, message=message)
            loop.quit()

    def on_full_frame(_frame) -> None:
        if outcome or window.files.refiner.pending:  # an OME-Zarr image: wait for its finest level
            return
        # Let pending layout requests run (the status bar's frame label just got new text).
        QApplication.sendPostedEvents()
        QApplication.processEvents()
        if outcome:
            return
        if window.grab().save(str(path), "PNG"):
            finish(0)
        else:
            finish(1, f"{path}: cannot write the screenshot there")

    window.show_error_dialogs = False
    window.errorReported.connect(lambda _title, message: finish(1, message))
    window.fullFrameShown.connect(on_full_frame)
    timer = QTimer()
    timer.setSingleShot(True)
    timer.timeout.connect(lambda: finish(1, f"no full-quality frame within {timeout_s:g} s"))
    timer.start(int(timeout_s * 1000))
    with (
        _guarded(lambda message: finish(3, ""), traceback),
        _quit_on_sigint(lambda: finish(130, "interrupted")),
    ):
        window.show()
        window.files.open_input(input, tf, scalars, renderer)
        if not outcome:
            loop.exec_()
    timer.stop()
    window.close()
    window.shutdown()
    status = int(outcome.get("status", 1))  # type: ignore[call-overload]
    message = str(outcome.get("message") or "")
    if status and message:
        print(f"volren: error: {message}" if status == 1 else f"volren: {message}", file=sys.stderr)
    return status
