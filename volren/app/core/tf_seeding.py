"""A 2D transfer function that looks like a 1D one: the first 2D TF a user switches to.

Why: switching the editor from 1D to 2D used to replace the edited TF with a default triangle, so
the picture changed completely and the user's work was gone unless they found Undo (issue 23).
Seeded instead, the 2D TF draws what the 1D one drew, apart from a staircase: one box widget per
stretch between the 1D TF's opacity points, over every gradient magnitude, with the 1D TF's colour
and opacity at the stretch's middle (the mean of its linear opacity there). The user then narrows
the boxes' gradient ranges to bring out boundaries.
"""

from __future__ import annotations

import numpy as np

from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TFWidget, TransferFunction2D


def seeded_2d(tf: TransferFunction1D, value_range: tuple[float, float], gradient_max: float) -> TransferFunction2D:
    """A 2D TF over `value_range` x [0, gradient_max] with `tf`'s colours and opacities along the value axis."""
    lo, hi = value_range
    inside = [x for x in tf.opacity_points[:, 0] if lo < x < hi]
    edges = np.unique(np.array([lo, *inside, hi], dtype=np.float64))
    centres = 0.5 * (edges[:-1] + edges[1:])
    rgb, alpha = tf.sample(centres)
    widgets = [
        TFWidget.box((a, b), (0.0, gradient_max), tuple(float(c) for c in colour), float(opacity))
        for a, b, colour, opacity in zip(edges[:-1], edges[1:], rgb, alpha, strict=True)
        if opacity > 0.0
    ]
    return TransferFunction2D((lo, hi), (0.0, gradient_max), widgets, tf.opacity_unit_distance)
