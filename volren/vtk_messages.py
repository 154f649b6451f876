"""Catch what VTK prints, so that its errors become VolrenErrors and its chatter stays quiet.

VTK reports problems by printing (through vtkOutputWindow, vtkLogger, or C++ code writing to
file descriptor 2) rather than raising, and returns an empty or half-filled result. Inside
`vtk_messages()` all of that is collected into a `MessageLog` instead of reaching the terminal.
Used by `volren.io` (readers) and the `vtk` renderer.
"""

from __future__ import annotations

import os
import sys
import tempfile
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Literal

from vtkmodules.vtkCommonCore import vtkOutputWindow, vtkStringOutputWindow


@dataclass(frozen=True)
class VtkMessage:
    """One message VTK printed: its kind ('error', 'warning' or 'text') and the text itself."""

    kind: Literal["error", "warning", "text"]
    text: str


@dataclass
class MessageLog:
    """Messages collected while VTK ran; filled when the `vtk_messages` block ends."""

    messages: list[VtkMessage] = field(default_factory=list)

    @property
    def errors(self) -> list[VtkMessage]:
        return [m for m in self.messages if m.kind == "error"]


def parse_output_window(text: str) -> list[VtkMessage]:
    """Split vtkStringOutputWindow's text into messages, dropping source paths and addresses."""
    out = []
    for block in text.split("\n\n"):
        block = block.strip()
        if not block:
            continue
        head, _, rest = block.partition("\n")
        kind: Literal["error", "warning", "text"] = "text"
        if head.startswith("ERROR"):
            kind = "error"
        elif "Warning" in head.split(":")[0]:
            kind = "warning"
        body = rest if kind != "text" and rest else block
        # "vtkXMLDataParser (0x55d...): message" -> "message"
        if "): " in body.split("\n")[0] and body.startswith("vtk"):
            body = body.split("): ", 1)[1]
        out.append(VtkMessage(kind, " ".join(body.split())))
    return out


@contextmanager
def _stderr_into(sink: list[str]) -> Iterator[None]:
    """Send file descriptor 2 to a temporary file: C++ code (MetaIO, vtkLogger) writes there directly."""
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError):  # no usable stderr: nothing to silence
        yield
        return
    with tempfile.TemporaryFile() as tmp:
        os.dup2(tmp.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            tmp.seek(0)
            sink.append(tmp.read().decode("utf-8", "replace"))


_VTK_LOCK = threading.RLock()


@contextmanager
def vtk_messages() -> Iterator[MessageLog]:
    """Catch everything VTK says inside the block instead of letting it reach the terminal.

    VTK's output window and file descriptor 2 belong to the whole process, so blocks run one at
    a time (a lock); anything another thread prints to stderr meanwhile is caught as well.
    """
    log = MessageLog()
    window = vtkStringOutputWindow()
    stderr_text: list[str] = []
    with _VTK_LOCK:
        previous = vtkOutputWindow.GetInstance()
        vtkOutputWindow.SetInstance(window)
        try:
            with _stderr_into(stderr_text):
                yield log
        finally:
            vtkOutputWindow.SetInstance(previous)
        text = window.GetOutput()
        if isinstance(text, bytes):  # VTK hands back bytes when a message is not valid UTF-8
            text = text.decode("utf-8", "replace")
        log.messages.extend(parse_output_window(text or ""))
        for chunk in stderr_text:
            lines = [" ".join(line.split()) for line in chunk.splitlines() if line.strip()]
            if lines:
                log.messages.append(VtkMessage("text", "; ".join(lines)))
