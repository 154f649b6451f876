"""The bricks of a whole uniform grid, for sort-last rendering.

A brick is a box of grid *cells* (`brick` per axis; the last along an axis may be smaller), as in
`model.bricks`: brick cells [first, end) read voxels first..end, so neighbours share a face of
voxels. Its sub-volume adds `ghost` voxels beyond every face inside the whole grid, where
interpolation, gradients and pre-integrated segments that reach past the face read the
neighbour's values. Its `Region` tells the renderer which part of each ray is the brick's own.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError
from volren.model.region import Region

Index3 = tuple[int, int, int]


@dataclass(frozen=True)
class Brick:
    """One brick: its place in the brick grid (bk, bj, bi) and its cells [first, end) as (i, j, k)."""

    index: Index3
    first: Index3
    end: Index3


@dataclass(frozen=True)
class BrickLayout:
    """A whole grid of `dimensions` (nx, ny, nz) voxels cut into bricks of `brick` cells per axis."""

    dimensions: Index3
    spacing: tuple[float, float, float]
    origin: tuple[float, float, float]
    value_range: tuple[float, float]
    brick: int

    def __post_init__(self) -> None:
        if isinstance(self.brick, bool) or not isinstance(self.brick, int | np.integer) or self.brick < 1:
            raise VolrenError(f"bricks must be at least 1 cell per side, got {self.brick!r}")
        if min(self.dimensions) < 2:
            raise VolrenError(f"a bricked volume needs at least 2 samples per axis, got {self.dimensions}")

    @property
    def cell_edges(self) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.intp]]:
        """Per axis (x, y, z): the first cell of every brick, then the number of cells."""
        return tuple(np.append(np.arange(0, n - 1, self.brick), n - 1) for n in self.dimensions)  # type: ignore[return-value]

    @property
    def shape(self) -> Index3:
        """Bricks along z, y, x."""
        return tuple(len(e) - 1 for e in self.cell_edges[::-1])  # type: ignore[return-value]

    @property
    def n_bricks(self) -> int:
        return int(np.prod(self.shape))

    def world_edges(self, axis: int) -> NDArray[np.float64]:
        """World coordinates of the brick faces along `axis` (0 = x)."""
        return self.origin[axis] + self.spacing[axis] * self.cell_edges[axis].astype(np.float64)

    def brick_at(self, index: Index3) -> Brick:
        bk, bj, bi = index
        ex, ey, ez = self.cell_edges
        return Brick(
            (int(bk), int(bj), int(bi)),
            (int(ex[bi]), int(ey[bj]), int(ez[bk])),
            (int(ex[bi + 1]), int(ey[bj + 1]), int(ez[bk + 1])),
        )

    def bricks(self) -> Iterator[Brick]:
        """Every brick, in C order of the brick grid."""
        for index in np.ndindex(*self.shape):
            yield self.brick_at(index)  # type: ignore[arg-type]

    def voxel_slices(self, brick: Brick, ghost: int) -> tuple[slice, slice, slice]:
        """The (z, y, x) slices of the brick's voxels and `ghost` more beyond every inner face."""
        out = []
        for axis in (2, 1, 0):
            n = self.dimensions[axis]
            out.append(slice(max(brick.first[axis] - ghost, 0), min(brick.end[axis] + ghost, n - 1) + 1))
        return tuple(out)  # type: ignore[return-value]

    def sub_origin(self, slices: tuple[slice, slice, slice]) -> tuple[float, float, float]:
        """World position of the first voxel of a sub-volume cut with `slices`."""
        starts = (slices[2].start, slices[1].start, slices[0].start)
        return tuple(o + h * s for o, h, s in zip(self.origin, self.spacing, starts, strict=True))  # type: ignore[return-value]

    @property
    def bounds(self) -> tuple[float, float, float, float, float, float]:
        out: list[float] = []
        for o, h, n in zip(self.origin, self.spacing, self.dimensions, strict=True):
            out += [o, o + h * (n - 1)]
        return tuple(out)  # type: ignore[return-value]

    def region(self, brick: Brick) -> Region:
        """The brick's `Region`: its cells' box, pushed out by a voxel where it meets the whole
        volume's boundary (so that points on the boundary belong to it)."""
        lo, hi = [], []
        for axis in range(3):
            o, h, n = self.origin[axis], self.spacing[axis], self.dimensions[axis]
            a, b = brick.first[axis], brick.end[axis]
            lo.append(o + h * (a if a > 0 else -1))
            hi.append(o + h * (b if b < n - 1 else n))
        return Region(tuple(lo), tuple(hi), self.bounds, self.value_range)  # type: ignore[arg-type]
