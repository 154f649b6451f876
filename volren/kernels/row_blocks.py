"""Frames rendered by numba kernels in blocks of rows, so that progress is reported as they go."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from contextlib import contextmanager

import numba

from volren.model.progress import ProgressCallback


def run_in_row_blocks(
    width: int,
    height: int,
    blocks: int,
    chunk_size: int,
    kernel: Callable[[int, int], None],
    progress: ProgressCallback | None,
) -> None:
    """Call kernel(first pixel, end pixel) for about `blocks` blocks of whole rows, with numba's
    parallel chunk size set to `chunk_size` meanwhile (rays of one chunk walk similar paths; the
    caller's setting comes back afterwards), and report the fraction of rows done after each."""
    rows = max(1, math.ceil(height / blocks))
    with parallel_chunk_size(chunk_size):
        for y0 in range(0, height, rows):
            y1 = min(height, y0 + rows)
            kernel(y0 * width, y1 * width)
            if progress is not None:
                progress(y1 / height)


@contextmanager
def parallel_chunk_size(chunk_size: int) -> Iterator[None]:
    """numba's parallel chunk size set to `chunk_size` meanwhile, the caller's back afterwards."""
    old_chunk = numba.get_parallel_chunksize()
    numba.set_parallel_chunksize(chunk_size)
    try:
        yield
    finally:
        numba.set_parallel_chunksize(old_chunk)
