"""Where a bricked render reads its bricks from: the values of a sub-block of the whole grid, and
the value range of every brick (to skip the ones a TF makes transparent without reading them)."""

from __future__ import annotations

import math
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from volren.bricked.layout import BrickLayout
from volren.model.bricks import BrickGrid
from volren.model.volume import UniformVolume


@runtime_checkable
class BrickSource(Protocol):
    """A whole uniform grid, read a block at a time."""

    name: str
    dimensions: tuple[int, int, int]
    spacing: tuple[float, float, float]
    origin: tuple[float, float, float]
    value_range: tuple[float, float]

    def read(self, slices: tuple[slice, slice, slice]) -> NDArray:
        """The values [z, y, x] of a block."""
        ...

    def brick_grid(self, layout: BrickLayout, ghost: int) -> BrickGrid | None:
        """Every brick's value range over its voxels and `ghost` more beyond each face, or a range
        containing it (None: unknown, every brick is read)."""
        ...


class VolumeSource:
    """An in-memory `UniformVolume` as a brick source."""

    def __init__(self, volume: UniformVolume) -> None:
        self.volume = volume
        self.name = volume.name
        self.dimensions = volume.dimensions
        self.spacing = volume.spacing
        self.origin = volume.origin
        self.value_range = volume.value_range
        self._grids: dict[tuple[int, int], BrickGrid] = {}

    def read(self, slices: tuple[slice, slice, slice]) -> NDArray:
        return self.volume.values[slices]

    def brick_grid(self, layout: BrickLayout, ghost: int) -> BrickGrid:
        """Built once per brick size and ghost width (a pass over the values), then reused."""
        key = (layout.brick, ghost)
        if key not in self._grids:
            grid = BrickGrid.from_array(self.volume.values, layout.brick, self.spacing, self.origin)
            self._grids[key] = grid.dilated(math.ceil(ghost / layout.brick))  # the neighbours hold the ghosts
        return self._grids[key]


def has_finite(values: NDArray) -> bool:
    return bool(np.issubdtype(values.dtype, np.integer) or np.isfinite(values).any())
