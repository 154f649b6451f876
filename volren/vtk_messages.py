"""Catch what VTK prints, so that its errors become VolrenErrors and its chatter stays quiet.

VTK reports problems by printing (through vtkOutputWindow and vtkLogger) rather than raising.
`vtk_messages()` captures that text while a block runs and restores VTK's own output after it;
`VtkMessages.errors` lists the error reports, and warnings go to Python logging.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

from vtkmodules.vtkCommonCore import vtkLogger, vtkOutputWindow, vtkStringOutputWindow

log = logging.getLogger("volren.vtk")

_HEADER = re.compile(r"^(ERROR|Warning|Generic Warning|Debug): In .*?, line \d+\s*$", re.MULTILINE)


@dataclass
class VtkMessages:
    errors: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)

    def first_error(self) -> str | None:
        return self.errors[0] if self.errors else None


def _split(text: str) -> list[tuple[str, str]]:
    """[(kind, one-line message)] from vtkStringOutputWindow's text."""
    parts = _HEADER.split(text)
    out = []
    for kind, body in zip(parts[1::2], parts[2::2]):
        lines = [ln.strip() for ln in body.strip().splitlines() if ln.strip()]
        if lines:
            # "vtkXMLImageDataReader (0x55...): Error opening file x" -> drop the object address
            out.append((kind, re.sub(r"^\w+ \(0x[0-9a-f]+\): ", "", lines[0])))
    return out


@contextmanager
def vtk_messages() -> Iterator[VtkMessages]:
    """Capture VTK's errors and warnings raised inside the block (not thread-safe, like VTK's)."""
    messages = VtkMessages()
    previous_window = vtkOutputWindow.GetInstance()
    previous_verbosity = vtkLogger.GetCurrentVerbosityCutoff()
    capture = vtkStringOutputWindow()
    vtkOutputWindow.SetInstance(capture)
    vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_OFF)
    try:
        yield messages
    finally:
        vtkOutputWindow.SetInstance(previous_window)
        vtkLogger.SetStderrVerbosity(vtkLogger.ConvertToVerbosity(previous_verbosity))
        for kind, text in _split(capture.GetOutput()):
            if kind == "ERROR":
                messages.errors.append(text)
            else:
                messages.warnings.append(text)
                log.warning("VTK: %s", text)
