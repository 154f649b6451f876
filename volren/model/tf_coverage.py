"""Does a transfer function show anything of a volume? A TF made for other data (its control points
far from the data's values) renders a black image, or one flat colour, and every renderer reports
success; this finds those cases so that callers can warn before drawing.
"""

from __future__ import annotations

import numpy as np

from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TransferFunction


def _range_text(lo: float, hi: float) -> str:
    return f"[{lo:.6g}, {hi:.6g}]"


def max_opacity_over(tf: TransferFunction1D, lo: float, hi: float) -> float:
    """The largest opacity of `tf` over the data values [lo, hi]: exact, since the opacity is
    piecewise linear and so peaks at an end of the range or at a control point inside it. A
    control point's own opacity counts, not the TF sampled at its value: at a step (two points at
    one value) sampling gives one side only, and a peak that drops to 0 at once would be missed.
    A point at `lo` counts only through the sample there: its other side holds values below `lo`."""
    points = tf.opacity_points
    xs = points[:, 0]
    inside = points[(xs > lo) & (xs <= hi), 1]
    _, alpha = tf.sample(np.array([lo, hi], dtype=np.float64))
    return float(max(alpha.max(), inside.max(initial=0.0)))


def coverage_problem(tf: TransferFunction, data_range: tuple[float, float]) -> str | None:
    """Why `tf` will show nothing useful of data in `data_range`, in words naming both ranges, or
    None. Two cases: zero opacity over all the data's values (a black image); control points that
    all lie outside the data's values (every value gets the same colour and opacity), unless the TF
    has a single control point and so is constant by design."""
    lo, hi = data_range
    tf_lo, tf_hi = tf.value_range
    ranges = f"the TF spans {_range_text(tf_lo, tf_hi)}, the data {_range_text(lo, hi)}"
    if isinstance(tf, TransferFunction1D):
        if max_opacity_over(tf, lo, hi) == 0.0:
            return f"the opacity is 0 over the volume's whole value range, so the image is black ({ranges})"
    elif not any(w.opacity > 0 for w in tf.widgets):
        return f"no widget has an opacity above 0, so the image is black ({ranges})"
    if tf_hi > tf_lo and (tf_hi < lo or tf_lo > hi):  # one control point: constant on purpose
        return f"the TF's range misses the data's, so every value gets the same colour and opacity ({ranges})"
    return None
