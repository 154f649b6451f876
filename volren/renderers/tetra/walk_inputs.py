"""What the cell walk (`traversal.cast_rays`) reads, bundled by what travels together (the rays:
`volren.kernels.ray_block.BinnedRays`).

Why bundles: the walk took 26 positional parameters, where moving one place still compiled and
drew a wrong image. numba types a `typing.NamedTuple` as a named tuple (arrays allowed as
members, fields read by name in nopython mode, cached kernels keep working while the class is
defined at module level), so each bundle reaches the kernel as one parameter.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray


class TetCells(NamedTuple):
    """The mesh as the walk reads it, cells in the walk's (Morton) order."""

    #: (m, 4) the cell across each face (-1: none)
    neighbors: NDArray[np.int64]
    #: (m, 4, 4) inward unit face planes (`traversal.pack_planes`)
    planes: NDArray[np.float64]
    #: the linear field: (m, 4) corner values, (m, 3) gradients, (m, 3) the point of the first corner
    values: NDArray[np.float64]
    gradients: NDArray[np.float64]
    corner: NDArray[np.float64]
    #: (m,) cells that are neither flat nor non-finite (the others are holes)
    usable: NDArray[np.bool_]
    #: a ray closer than this (world units) to a face plane lies in it
    on_plane: float


class WalkedSet(NamedTuple):
    """The cells a walk runs through and integrates."""

    #: (m, 4) faces where a walk can enter the walked cells
    boundary: NDArray[np.bool_]
    #: (m,) cells a walk may run through at positive length
    walkable: NDArray[np.bool_]
    #: (m,) cells the TF makes visible (the others add nothing to a composite)
    visible: NDArray[np.bool_]


class SegmentTable(NamedTuple):
    """The 3D pre-integration table of a cell segment (`optical_tables`): value s sits at entry
    (s - lo) * scale, segment lengths run up to lmax."""

    #: (n, n, 1) optical depth per unit length
    depth_per_length: NDArray[np.float64]
    #: (K, n, n, 3) colour per unit opacity at K evenly spaced lengths
    colour_ratio: NDArray[np.float64]
    lo: float
    scale: float
    lmax: float


class WalkOptions(NamedTuple):
    """How the rays are combined: the blend mode (`traversal.COMPOSITE` ...), the opacity at which a
    ray stops, and the most cells one walk may take."""

    mode: int
    termination: float
    max_steps: int
