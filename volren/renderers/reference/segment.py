"""The reference integral of one segment on which the value runs linearly: the truth that
pre-integration tables are compared with.

Why: a pre-integration table entry approximates exactly what the reference integrates along a ray
inside one tetrahedron, so its adaptive integrator (exact cuts at TF breakpoints, h^2 refinement
until two levels agree to `tol`) run on a single linear interval is that entry's exact value.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from volren.errors import VolrenError
from volren.kernels.shading import ShadeParams
from volren.kernels.tf_eval import pack_tf
from volren.model.transfer_function import TransferFunction1D
from volren.renderers.reference.ray_inputs import Quadrature, RayIntervals
from volren.renderers.reference.ray_integral import COMPOSITE
from volren.renderers.reference.refinement import integrate_ray

#: Shading off (the other entries are unused then).
_NO_SHADING = ShadeParams(False, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)


def segment_rgba(
    tf: TransferFunction1D,
    fronts: ArrayLike,
    backs: ArrayLike,
    length: float,
    tol: float = 1e-10,
    max_levels: int = 24,
) -> NDArray[np.float64]:
    """(k, 4) premultiplied RGBA of segments of `length` whose value runs from fronts[k] to backs[k]."""
    fronts = np.asarray(fronts, dtype=np.float64).reshape(-1)
    backs = np.asarray(backs, dtype=np.float64).reshape(-1)
    packed = pack_tf(tf)
    out = np.empty((len(fronts), 4))
    ta = np.zeros(1)
    tb = np.array([float(length)])
    shading = np.zeros((0, 3, 4))
    quad = Quadrature(COMPOSITE, length / 4, tol, max_levels)
    for k, (front, back) in enumerate(zip(fronts, backs, strict=True)):
        poly = np.array([[front, (back - front) / length, 0.0, 0.0]])
        intervals = RayIntervals(ta, tb, poly, shading, 1)
        r, g, b, a, _, _, converged, _ = integrate_ray(
            intervals, quad, packed, None, _NO_SHADING, 0.0, 0.0, 1.0
        )
        if not converged:
            raise VolrenError(f"the segment integral from {front} to {back} did not converge to {tol}")
        out[k] = (r, g, b, a)
    return out
