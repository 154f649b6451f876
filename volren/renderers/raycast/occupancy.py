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
    distance = np.zeros(empty.shape, np.int8)
    distance[empty] = 1
    box = empty
    for d in range(2, cap + 1):
        # bricks whose 26-neighbours all lie in `box`: one erosion by a 3x3x3 cube, axis by axis
        for axis in range(3):
            pad = [(1, 1) if a == axis else (0, 0) for a in range(3)]
            padded = np.pad(box, pad, constant_values=True)
            n = box.shape[axis]
            box = (padded.take(range(0, n), axis=axis) & padded.take(range(1, n + 1), axis=axis)
                   & padded.take(range(2, n + 2), axis=axis))  # fmt: skip
        if not box.any():
            break
        distance[box] = d
    return distance
