"""Progress bars only on a terminal: logs and pipes get none of tqdm's carriage returns."""

from __future__ import annotations

import io

from volren.cli.progress import progress_bar


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def draw(stream) -> str:
    with progress_bar("engine vtk 512x512", file=stream, delay=0.0) as progress:
        for k in range(11):
            progress(k / 10)
    return stream.getvalue()


def test_a_terminal_gets_the_bar_and_a_pipe_does_not():
    assert "engine vtk 512x512" in draw(Terminal())
    assert draw(io.StringIO()) == ""
