"""A procedural uint16 volume of any size, generated a block at a time (never whole in memory):
what `python -m benchmarks.scale` writes into OME-Zarr pyramids from 256^3 to 2048^3.

The field: Marschner and Lobb's test signal (smooth, with detail at every scale the grid can
hold) inside a sphere, zero outside it, so that the scene has empty space to skip like real
scans, scaled to 0..60000.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

#: Marschner-Lobb parameters (the paper's alpha and f_M).
ALPHA = 0.25
F_M = 6.0
PEAK = 60000.0


class ProceduralVolume:
    """`n`^3 samples over [-1, 1]^3 (z, y, x), uint16, sliced like a numpy array."""

    dtype = np.dtype(np.uint16)

    def __init__(self, n: int) -> None:
        self.n = int(n)
        self.shape = (self.n,) * 3

    @property
    def spacing(self) -> tuple[float, float, float]:
        h = 2.0 / (self.n - 1)
        return (h, h, h)

    @property
    def origin(self) -> tuple[float, float, float]:
        return (-1.0, -1.0, -1.0)

    def __getitem__(self, where: tuple[slice, slice, slice]) -> NDArray[np.uint16]:
        axes = [np.linspace(-1.0, 1.0, self.n, dtype=np.float32)[s] for s in where]
        z, y, x = np.meshgrid(*axes, indexing="ij", sparse=True)
        r = np.sqrt(x * x + y * y)
        rho = np.cos(2.0 * np.pi * F_M * np.cos(np.pi * r / 2.0))
        value = (1.0 - np.sin(np.pi * z / 2.0) + ALPHA * (1.0 + rho)) / (2.0 * (1.0 + ALPHA))
        inside = x * x + y * y + z * z <= 0.81
        return np.where(inside, np.rint(value * PEAK), 0).astype(np.uint16)
