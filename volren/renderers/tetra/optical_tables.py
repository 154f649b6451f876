"""The pre-integration table turned into what the tetra walk reads: optical depth per unit length
and colour per unit opacity.

Why its own kernel: the numpy version made four float64 temporaries of the whole (L, n, n, 4)
table (67 MB at 256 x 256 x 32) and took 250 ms of every TF edit on oxygen, twice the table
itself; one parallel pass over the entries takes a few milliseconds.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

#: Opacities are clamped below 1 so that the optical depth stays finite.
MAX_ALPHA = 1.0 - 1e-7


@njit(nogil=True, parallel=True, cache=True)
def _split(table, first_length, depth, ratio):
    layers, n = table.shape[0], table.shape[1]
    for i in prange(n):
        for j in range(n):
            a0 = min(np.float64(table[0, i, j, 3]), MAX_ALPHA)
            depth[i, j, 0] = -math.log1p(-a0) / first_length
            for k in range(layers):
                a = min(np.float64(table[k, i, j, 3]), MAX_ALPHA)
                for c in range(3):
                    ratio[k, i, j, c] = np.float64(table[k, i, j, c]) / a if a > 0.0 else 0.0


def optical_tables(
    table: NDArray[np.floating], first_length: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(depth (n, n, 1): optical depth per unit length from the first length layer, ratio (L, n, n, 3):
    premultiplied colour over opacity, 0 where the opacity is 0) of a table (L, n, n, 4)."""
    layers, n = table.shape[0], table.shape[1]
    depth = np.empty((n, n, 1))
    ratio = np.empty((layers, n, n, 3))
    _split(np.ascontiguousarray(table), float(first_length), depth, ratio)
    return depth, ratio
