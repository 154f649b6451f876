"""Everything the `volren` command says on stderr is one line starting with ``volren: ``.

Libraries speak in several ways: Python warnings (numpy's overflow RuntimeWarnings, numba's
performance warnings, pyvista's UserWarnings), the `logging` module, and VTK's output window and
logger, which print multi-line blocks with source paths. `one_line_messages()` routes all of them
through one `LinePrinter` while a command runs: each message folded onto one line, and printed
once however often it recurs (a warning raised in a loop, or from several call sites).
"""

from __future__ import annotations

import logging
import sys
import warnings
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path
from typing import Any, TextIO

from volren.errors import VolrenWarning

#: Longest message of another library printed whole: VTK appends object dumps (a vtkInformation's
#: every key) to some, and the first characters say what went wrong.
LIBRARY_MESSAGE_CHARS = 300


def fold(text: object) -> str:
    """`text` on one line: runs of whitespace, newlines included, become one space."""
    return " ".join(str(text).split())


def shorten(text: str, limit: int = LIBRARY_MESSAGE_CHARS) -> str:
    """`text` folded, and cut after `limit` characters (marked with ' ...')."""
    line = fold(text)
    return line if len(line) <= limit else line[:limit] + " ..."


def _package(path: str) -> str:
    """The installed package a source file belongs to ('pyvista' for .../site-packages/pyvista/x.py)."""
    parts = Path(path).parts
    for anchor in ("site-packages", "dist-packages"):
        if anchor in parts[:-1]:
            return parts[parts.index(anchor) + 1]
    return Path(path).stem


class LinePrinter:
    """Prints ``volren: warning: ...`` lines, each distinct message once."""

    def __init__(self, stream: TextIO | None = None) -> None:
        self._stream = stream
        self._seen: set[str] = set()

    def warn(self, text: object, origin: str = "") -> None:
        """Print `text` folded, with `origin` after it in brackets, unless the text was printed."""
        line = fold(text)
        if not line or line in self._seen:
            return
        self._seen.add(line)
        suffix = f" ({origin})" if origin else ""
        print(f"volren: warning: {line}{suffix}", file=self._stream or sys.stderr, flush=True)

    def showwarning(
        self,
        message: Any,
        category: type[Warning],
        filename: str,
        lineno: int,
        file: Any = None,
        line: Any = None,
    ) -> None:
        """`warnings.showwarning`'s signature. Our own warnings name what is at fault already;
        another library's gets its category and where it was raised, for a bug report."""
        if issubclass(category, VolrenWarning):
            self.warn(message)
        else:
            where = "/".join(Path(filename).parts[-2:])
            self.warn(shorten(str(message)), f"{category.__name__} at {where}:{lineno}")


class _LoggingHandler(logging.Handler):
    """A logging handler that hands WARNING and worse records to a LinePrinter, named by their
    logger or, for the root logger, by the package that logged (pyvista logs VTK's errors there)."""

    def __init__(self, printer: LinePrinter) -> None:
        super().__init__(logging.WARNING)
        self._printer = printer

    def emit(self, record: logging.LogRecord) -> None:
        try:
            source = record.name if record.name != "root" else _package(record.pathname)
            self._printer.warn(f"{source}: {shorten(record.getMessage())}")
        except Exception:  # a log call must never break the command
            self.handleError(record)


@contextmanager
def _logging_to(printer: LinePrinter) -> Iterator[None]:
    """Route the root logger (where library loggers propagate) to `printer`; without a handler,
    Python's last-resort handler would print each record as is, lines and all."""
    root = logging.getLogger()
    handler = _LoggingHandler(printer)
    root.addHandler(handler)
    try:
        yield
    finally:
        root.removeHandler(handler)


@contextmanager
def _vtk_output_to(printer: LinePrinter) -> Iterator[None]:
    """VTK messages printed outside a `volren.vtk_messages` block (which catches and judges its
    own) reach `printer` as one line each instead of vtkLogger's coloured multi-line blocks."""
    try:
        from vtkmodules.util.misc import calldata_type
        from vtkmodules.util.vtkConstants import VTK_STRING
        from vtkmodules.vtkCommonCore import vtkLogger, vtkOutputWindow
    except ImportError:  # no VTK: nothing of it to catch
        yield
        return
    from volren.vtk_messages import parse_output_window

    @calldata_type(VTK_STRING)
    def on_text(_obj: Any, _event: str, output: str) -> None:
        for message in parse_output_window(output or ""):
            printer.warn(f"VTK: {shorten(message.text)}")

    window = vtkOutputWindow.GetInstance()
    mode = window.GetDisplayMode()
    verbosity = vtkLogger.GetCurrentVerbosityCutoff()
    tag = window.AddObserver("MessageEvent", on_text)
    window.SetDisplayModeToNever()
    vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_OFF)
    try:
        yield
    finally:
        window.RemoveObserver(tag)
        window.SetDisplayMode(mode)
        vtkLogger.SetStderrVerbosity(vtkLogger.ConvertToVerbosity(verbosity))


@contextmanager
def one_line_messages(printer: LinePrinter | None = None) -> Iterator[LinePrinter]:
    """While the block runs, warnings, log records and stray VTK output become one line each."""
    printer = printer or LinePrinter()
    with ExitStack() as stack:
        stack.enter_context(_logging_to(printer))
        stack.enter_context(_vtk_output_to(printer))
        previous = warnings.showwarning
        warnings.showwarning = printer.showwarning
        stack.callback(setattr, warnings, "showwarning", previous)
        yield printer
