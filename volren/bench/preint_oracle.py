"""The continuous pre-integration integral of one table entry, float64 and adaptive.

Why: `preintegrate`'s tables are compared with the integral they approximate, not with another
table. The integral of a segment whose value runs linearly from s_front to s_back is exactly
what the `reference` renderer integrates along a ray inside one tetrahedron, so its adaptive
integrator (exact cuts at TF breakpoints, h^2 refinement until two levels agree to `tol`) is
used on a single linear interval.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from volren.model.transfer_function import TransferFunction1D
from volren.renderers.reference.ray_integral import COMPOSITE, integrate_ray
from volren.renderers.reference.tf_eval import pack_tf

#: Shading off (the other entries are unused then).
_NO_SHADING = (False, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)


def continuous_entries(
    tf: TransferFunction1D,
    fronts: NDArray,
    backs: NDArray,
    length: float,
    tol: float = 1e-10,
    max_levels: int = 24,
) -> NDArray[np.float64]:
    """(k, 4) premultiplied RGBA of segments of `length` from fronts[k] to backs[k]."""
    packed = pack_tf(tf)
    out = np.empty((len(fronts), 4))
    ta = np.zeros(1)
    tb = np.array([float(length)])
    shading = np.zeros((0, 3, 4))
    for k, (front, back) in enumerate(zip(fronts, backs)):
        poly = np.array([[float(front), (float(back) - float(front)) / length, 0.0, 0.0]])
        r, g, b, a, _, _, converged, _ = integrate_ray(
            ta, tb, poly, shading, 1, COMPOSITE, length / 4, tol, max_levels, packed, _NO_SHADING, 0.0, 0.0, 1.0
        )
        if not converged:
            raise RuntimeError(f"the continuous integral from {front} to {back} did not converge to {tol}")
        out[k] = (r, g, b, a)
    return out
