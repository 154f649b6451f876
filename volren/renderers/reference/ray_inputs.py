"""What the reference's kernels read, bundled by what travels together.

Why bundles: the kernels took 14-18 positional parameters, where moving one place still compiled
and gave a wrong integral. numba types a `typing.NamedTuple` as a named tuple (arrays allowed as
members, fields read by name in nopython mode, cached kernels keep working while the class is
defined at module level), so each bundle reaches a kernel as one parameter.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray


class Quadrature(NamedTuple):
    """How a ray is integrated: the blend mode (`ray_integral.COMPOSITE` ...), the level-0 step h0
    (world units), the tolerance between two levels and the most levels (`refinement.integrate_ray`)."""

    mode: int
    step: float
    tolerance: float
    max_levels: int


class RayIntervals(NamedTuple):
    """One ray's intervals front to back: on [starts[k], ends[k]] the scalar is
    s(starts[k] + u) = values[k] . (1, u, u^2, u^3) and, when gradients are needed, gradient
    component c is gradients[k, c] . (1, u, u^2, u^3) (`ray_integral`)."""

    starts: NDArray[np.float64]
    ends: NDArray[np.float64]
    values: NDArray[np.float64]
    gradients: NDArray[np.float64]
    #: how many of the rows are intervals
    n_intervals: int


class GridBox(NamedTuple):
    """A uniform grid's values (z, y, x) with its world origin and spacing (x, y, z), and the box
    rays are clipped to (`uniform.render_uniform`)."""

    values: NDArray[np.float64]
    origin: NDArray[np.float64]
    spacing: NDArray[np.float64]
    lo: NDArray[np.float64]
    hi: NDArray[np.float64]
    #: (m, 4) world half-spaces rays are clipped to besides the box (`volren.kernels.clip_planes`)
    planes: NDArray[np.float64]
    #: draw the cut faces where rays enter through a plane (`volren.kernels.cut_faces`)
    cap: bool


class CellPlanes(NamedTuple):
    """A tetrahedral mesh as `volren.kernels.tet_clipping.clip_tet` reads it (the arrays of
    `volren.model.tet_mesh.FacePlanes`)."""

    normals: NDArray[np.float64]
    anchors: NDArray[np.float64]
    sigma: NDArray[np.float64]
    values: NDArray[np.float64]
    gradients: NDArray[np.float64]
