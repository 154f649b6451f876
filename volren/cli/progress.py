"""tqdm progress bars for long renders and movies: shown only once the work takes more than a
second, and only on a terminal (a log file or a pipe gets no carriage-return noise)."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import TextIO

from tqdm import tqdm

from volren.renderers.base import ProgressCallback


@contextmanager
def progress_bar(
    description: str, file: TextIO | None = None, delay: float = 1.0
) -> Iterator[ProgressCallback]:
    """A progress callback drawing a bar on `file` (stderr) when it is a terminal."""
    bar = tqdm(
        total=1000,
        desc=description,
        delay=delay,
        leave=False,
        unit="‰",
        file=file,
        disable=None,
        bar_format="{l_bar}{bar}| {elapsed}<{remaining}",
    )

    def update(fraction: float) -> None:
        target = int(round(min(max(fraction, 0.0), 1.0) * 1000))
        if target > bar.n:
            bar.update(target - bar.n)

    try:
        yield update
    finally:
        bar.close()


@contextmanager
def frame_bar(
    description: str, frames: int, file: TextIO | None = None, delay: float = 1.0
) -> Iterator[ProgressCallback]:
    """A movie's progress callback (the fraction of the movie done), drawing whole frames on `file`."""
    bar = tqdm(
        total=frames, desc=description, delay=delay, leave=False, unit="frame", file=file, disable=None
    )

    def update(fraction: float) -> None:
        done = int(min(max(fraction, 0.0), 1.0) * frames + 1e-9)
        if done > bar.n:
            bar.update(done - bar.n)

    try:
        yield update
    finally:
        bar.close()
