"""A 2D transfer function that looks like a 1D one: the first 2D TF a user switches to.

Why: switching the editor from 1D to 2D must not change the picture; the user then narrows or
moves things in gradient magnitude to bring out boundaries. The 2D TF holds one `1d` widget, the
1D TF's own colour and opacity points as a band over the whole gradient axis, so at every gradient
magnitude it draws exactly what the 1D TF draws (same colours, same opacities per unit distance).
A staircase of boxes, one per stretch between opacity points, flattened every ramp to its middle
value: a viridis ramp turned into one flat cyan box, opaque down to the bottom of the ramp.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TFWidget, TransferFunction2D


def _reaching(points: NDArray[np.float64], lo: float, hi: float) -> NDArray[np.float64]:
    """`points` with their end values repeated at lo and hi where they stop short of them: the
    same function (constant beyond the ends), whose band the editor draws across the value axis."""
    first, last = points[:1].copy(), points[-1:].copy()
    first[0, 0], last[0, 0] = lo, hi
    return np.concatenate([first[: int(lo < points[0, 0])], points, last[: int(hi > points[-1, 0])]])


def seeded_2d(
    tf: TransferFunction1D, value_range: tuple[float, float], gradient_max: float
) -> TransferFunction2D:
    """A 2D TF over `value_range` x [0, gradient_max] that draws what `tf` draws, at every gradient."""
    lo, hi = value_range
    profile = TransferFunction1D(_reaching(tf.color_points, lo, hi), _reaching(tf.opacity_points, lo, hi))
    widget = TFWidget.from_1d(profile, (0.0, gradient_max))
    return TransferFunction2D(value_range, (0.0, gradient_max), [widget], tf.opacity_unit_distance)
