"""A block of pixel rays with the cells each may meet, as one kernel parameter.

Why: the mesh renderers (tetra's walk, the reference's clipping) hand their kernels the same arrays per block of rows; numba types a `typing.NamedTuple` as a named tuple (arrays as members,
fields read by name in nopython mode, cached kernels keep working while the class is defined at
module level), so they travel together and cannot be passed one place off.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray


class BinnedRays(NamedTuple):
    """n rays and their candidate cells (`tet_projection.bin_rows` and the like)."""

    #: (n, 3) origins on the near plane and unit directions, world space
    origins: NDArray[np.float64]
    directions: NDArray[np.float64]
    #: (n,) the ray parameter of the far plane (`tet_projection.ray_far`)
    far: NDArray[np.float64]
    #: ray q's candidates are candidates[offsets[q]:offsets[q + 1]] (cell ids)
    offsets: NDArray[np.int64]
    candidates: NDArray[np.int64]
    #: (m, 4) world half-spaces the rays are clipped to (`volren.kernels.clip_planes`)
    planes: NDArray[np.float64]
    #: draw the cut faces where rays enter through a plane (`volren.kernels.cut_faces`)
    cap: bool
