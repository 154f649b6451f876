"""How fast this machine runs right now: a chain of dependent multiply-adds (the core's latency and
clock) and a 32 MB fill (memory bandwidth), printed next to the load average in the reports.

Why: the project's 2-core machine has run the same commit 2-4x slower from one day to the next
(docs/shearwarp.md, stops 48 and 49) with the load average near 1 all the while, so absolute times
from different days do not compare; these two numbers say by how much the machine itself moved.
Ratios between renderers in one run stay the measure.

    python -m benchmarks.machine_speed
"""

from __future__ import annotations

import time

import numpy as np
from numba import njit

#: Iterations of the dependent chain, and the fill's size in float64 values (32 MB).
CHAIN = 2_000_000
FILL = 4 * 1024 * 1024


@njit(cache=True)
def _chain(n: int) -> float:
    x = 1.0
    for _ in range(n):
        x = x * 1.0000001 + 1e-9
    return x


def chain_ns(repeats: int = 5) -> float:
    """Nanoseconds per link of a dependent multiply-add chain (median of `repeats`)."""
    _chain(10)
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        _chain(CHAIN)
        times.append(time.perf_counter() - start)
    return float(np.median(times)) / CHAIN * 1e9


def fill_gbs(repeats: int = 5) -> float:
    """GB/s of filling a 32 MB float64 array already paged in (median of `repeats`)."""
    buffer = np.empty(FILL)
    buffer.fill(0.0)
    times = []
    for value in range(repeats):
        start = time.perf_counter()
        buffer.fill(float(value))
        times.append(time.perf_counter() - start)
    return buffer.nbytes / float(np.median(times)) / 1e9


def machine_line() -> str:
    """One line for a report: the probe's two numbers."""
    return f"machine speed: {chain_ns():.2f} ns a dependent multiply-add, {fill_gbs():.1f} GB/s filling 32 MB"


if __name__ == "__main__":
    print(machine_line())
