"""Which bricks a ray must sample, and how far the empty space around each brick reaches.

Why a distance and not a bit: a ray crossing a large empty region brick by brick pays a DDA step per
brick; with the Chebyshev distance to the nearest brick it must sample, it leaves the whole empty box
around it in one jump (distance-field skipping, Real-Time Volume Graphics section 8.4 / Cohen and
Sheffer's proximity clouds).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

#: Distances are counted up to this many bricks (a larger box saves little and costs a pass each).
MAX_DISTANCE = 8


def empty_distance(visible: NDArray[np.bool_], cap: int = MAX_DISTANCE) -> NDArray[np.int8]:
    """Per brick (z, y, x): 0 where `visible`; else d >= 1 such that every brick within Chebyshev
    distance d - 1 of it is empty (bricks outside the grid count as empty), d at most `cap` (at
    most 127: a byte per brick, a quarter of the cache lines a ray's brick walk reads as int32)."""
    if not 1 <= cap <= 127:
        raise ValueError(f"cap must be 1 to 127 (a byte per brick), got {cap}")
    empty = ~np.asarray(visible, dtype=bool)
    distance = empty.astype(np.int8)
    box = empty
    for _ in range(2, cap + 1):
        box = _eroded(box)
        if not box.any():
            break
        distance += box  # the boxes shrink: a brick in the d-th box is in every one before it
    return distance


def _eroded(box: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """The bricks whose 26 neighbours all lie in `box` (outside the grid counts as inside): one
    erosion by a 3x3x3 cube, axis by axis, on slices in memory order rather than padded copies."""
    out = box.copy()
    for axis in range(3):
        head = tuple(slice(1, None) if a == axis else slice(None) for a in range(3))
        tail = tuple(slice(None, -1) if a == axis else slice(None) for a in range(3))
        shrunk = out.copy()
        shrunk[head] &= out[tail]
        shrunk[tail] &= out[head]
        out = shrunk
    return out
