"""A transfer function part way between two others, for TF keyframes in movies.

Two piecewise-linear functions blended with weight w are again piecewise linear, with corners at
the union of both functions' corners: so the blend of two 1D TFs is exact when both are sampled
at every corner of either (a step, two points at one value, keeps both sides). 2D TFs blend
widget by widget, which needs the same widgets, in the same order, of the same types.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TFWidget, TransferFunction, TransferFunction2D


def _one_sided(points: NDArray[np.float64], xs: NDArray[np.float64]) -> tuple[NDArray, NDArray]:
    """The (left, right) limits of a piecewise-linear function given by sorted `points` (x in
    column 0, values after) at `xs`: they differ only where the function steps."""
    x, values = points[:, 0], points[:, 1:]
    first = np.searchsorted(x, xs, side="left")
    last = np.searchsorted(x, xs, side="right") - 1
    interpolated = np.stack([np.interp(xs, x, column) for column in values.T], axis=1)
    at_corner = (first < len(x)) & (x[np.minimum(first, len(x) - 1)] == xs)
    left = np.where(at_corner[:, None], values[np.minimum(first, len(x) - 1)], interpolated)
    right = np.where(at_corner[:, None], values[np.maximum(last, 0)], interpolated)
    return left, right


def _blend_points(a: NDArray[np.float64], b: NDArray[np.float64], weight: float) -> NDArray[np.float64]:
    xs = np.union1d(a[:, 0], b[:, 0])
    a_left, a_right = _one_sided(a, xs)
    b_left, b_right = _one_sided(b, xs)
    left = (1 - weight) * a_left + weight * b_left
    right = (1 - weight) * a_right + weight * b_right
    rows = []
    for x, lo, hi in zip(xs, left, right, strict=True):
        rows.append([x, *lo])
        if not np.array_equal(lo, hi):
            rows.append([x, *hi])
    out = np.asarray(rows)
    out[:, 1:] = np.clip(out[:, 1:], 0.0, 1.0)  # (1 - w) + w may round past 1
    return out


def _mix(a, b, weight: float):
    if isinstance(a, tuple):
        return tuple((1 - weight) * p + weight * q for p, q in zip(a, b, strict=True))
    return (1 - weight) * a + weight * b


def _blend_field(a, b, weight: float):
    """A geometry field blended: numbers and pairs linearly, a 1d widget's points as 1D TFs blend."""
    if isinstance(a, tuple) and isinstance(a[0], tuple):
        return _blend_points(np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64), weight)
    return _mix(a, b, weight)


def _blend_widgets(a: TFWidget, b: TFWidget, weight: float, index: int) -> TFWidget:
    if a.type != b.type:
        raise VolrenError(f"cannot blend 2D transfer functions: widget {index} is a {a.type} in one and a {b.type} "
                          "in the other")  # fmt: skip
    fields = {key: _blend_field(getattr(a, key), getattr(b, key), weight) for key in a.geometry}
    return TFWidget(a.type, _mix(a.color, b.color, weight), _mix(a.opacity, b.opacity, weight), **fields)


def blend_transfer_functions(a: TransferFunction, b: TransferFunction, weight: float) -> TransferFunction:
    """(1 - weight) a + weight b: `a` at 0, `b` at 1 (new TFs; neither input changes)."""
    if weight <= 0:
        return a.copy()
    if weight >= 1:
        return b.copy()
    unit = _mix(a.opacity_unit_distance, b.opacity_unit_distance, weight)
    if isinstance(a, TransferFunction1D) and isinstance(b, TransferFunction1D):
        color = _blend_points(a.color_points, b.color_points, weight)
        opacity = _blend_points(a.opacity_points, b.opacity_points, weight)
        return TransferFunction1D(color, opacity, unit, a.extra)
    if isinstance(a, TransferFunction2D) and isinstance(b, TransferFunction2D):
        if len(a.widgets) != len(b.widgets):
            raise VolrenError(f"cannot blend 2D transfer functions with {len(a.widgets)} and {len(b.widgets)} widgets: "
                              "TF keyframes of a 2D TF need the same widgets")  # fmt: skip
        widgets = [
            _blend_widgets(p, q, weight, i) for i, (p, q) in enumerate(zip(a.widgets, b.widgets, strict=True))
        ]
        value_range = _mix(a.value_range, b.value_range, weight)
        gradient_range = _mix(a.gradient_range, b.gradient_range, weight)
        return TransferFunction2D(value_range, gradient_range, widgets, unit, a.extra)
    raise VolrenError(
        f"cannot blend a {a.dims}D and a {b.dims}D transfer function: TF keyframes need one kind"
    )
