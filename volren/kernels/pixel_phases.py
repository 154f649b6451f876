"""Each pixel's phase: where its ray's segment boundaries fall (`sample_placement`'s rule).

Why a module of its own: the phases are numpy, needed once per image size, and a renderer whose
march is not numba's (raycast's C march) must get them without importing numba.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def pixel_phases(mode: str, width: int, height: int, seed: int) -> NDArray[np.float64]:
    """The phase in [0, 1) of every pixel's segment boundaries (row-major, row 0 at the top):
    `midpoint` (0), `interleaved` (0 and 1/2 on a checkerboard: neighbouring pixels sample half a
    step apart), `random` (seeded)."""
    if mode == "midpoint":
        return np.zeros(width * height)
    if mode == "interleaved":
        jj, ii = np.mgrid[0:height, 0:width]
        return np.where((ii + jj) % 2 == 0, 0.0, 0.5).reshape(-1)
    return np.random.default_rng(seed).random(width * height)
