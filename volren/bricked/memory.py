"""Keeping a streaming process's resident memory at what it holds.

Why: glibc's malloc serves blocks of 128 KiB and more with mmap, returned to the system when
freed, but it raises that threshold to the size of any such block freed (up to 32 MiB). After a
frame's first full-size image is freed, every chunk (512 KiB) comes from the heap instead, and a
heap that chunks are evicted from in LRU order cannot shrink: the process grew to 3.4 GiB while
its chunk cache held 2 GiB (1024^3 uint16 streamed at --memory 2GB). Fixing the threshold
(`mallopt`) keeps large blocks on mmap, so freed chunks leave at once.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools
import sys

#: mallopt parameters (malloc.h).
M_TRIM_THRESHOLD = -1
M_MMAP_THRESHOLD = -3
LARGE_BLOCK = 128 * 1024


@functools.cache
def keep_large_blocks_on_mmap() -> bool:
    """Fix glibc's mmap threshold at 128 KiB for this process (once); False where there is no
    glibc (macOS, Windows, musl), which manage memory their own way."""
    if not sys.platform.startswith("linux"):
        return False
    name = ctypes.util.find_library("c")
    if not name:
        return False
    try:
        libc = ctypes.CDLL(name)
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes = (ctypes.c_int, ctypes.c_int)
    return bool(mallopt(M_MMAP_THRESHOLD, LARGE_BLOCK)) and bool(mallopt(M_TRIM_THRESHOLD, LARGE_BLOCK))
