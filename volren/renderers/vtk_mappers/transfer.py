"""Our transfer function expressed in VTK's terms, so that VTK draws DESIGN.md's optical model.

Uniform mappers (smart, GPU ray cast, fixed point) share our convention: the opacity a of a
slab `ScalarOpacityUnitDistance` thick, corrected per sample as 1 - (1 - a)^(h / d). They get the
control points as they are.

The unstructured mappers (ray cast, projected tetrahedra, ZSweep) differ twice (measured, see
../shared/scenes/README.md):
- they read the opacity value y as an extinction y / d per unit length, where our model has
  -ln(1 - a) / d; so we hand them y = -ln(1 - min(a, 1 - 1e-6)), and since that is not linear in
  s where a is, we add nodes inside each interval where the opacity changes until linear
  interpolation of y is close to the exact curve;
- they read the opacity function only at colour nodes, so every node carries both a colour and
  an opacity.

Non-finite data values are replaced by a sentinel one data-range below the finite minimum, and
every value below the finite minimum is made transparent; interpolation next to a NaN sample then
mostly lands in that transparent band, approximating the reference's rule (a sample interpolated
from a NaN is transparent).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from volren.model.transfer_function import MAX_OPACITY, TransferFunction1D
from volren.renderers.vtk_mappers._vtk import vtkColorTransferFunction, vtkPiecewiseFunction

#: Largest step of -ln(1 - a) between neighbouring nodes handed to the unstructured mappers.
MAX_EXTINCTION_STEP = 0.02
MAX_SUBDIVISIONS = 256


def replace_nonfinite(values: NDArray, data_range: tuple[float, float]) -> tuple[NDArray, float | None]:
    """`values` with NaN/Inf replaced by a sentinel below the data, and the sentinel (or None)."""
    if np.issubdtype(values.dtype, np.integer) or np.all(np.isfinite(values)):
        return values, None
    lo, hi = data_range
    span = hi - lo if hi > lo else max(abs(lo), 1.0)
    sentinel = lo - span
    out = np.array(values, copy=True)
    out[~np.isfinite(out)] = sentinel
    return out, sentinel


def _transparent_below(xs: NDArray, alphas: NDArray, tf: TransferFunction1D, data_lo: float, sentinel: float):
    """Opacity nodes that are 0 below the finite data minimum, unchanged from it up.

    The step sits 1-2 % of the data range below the minimum, wide enough for VTK's lookup tables
    (sized from the smallest node gap) and narrow enough to catch almost every sample
    interpolated from a NaN one.
    """
    keep = xs >= data_lo
    _, a_lo = tf.sample(np.array([data_lo]))
    band = (data_lo - sentinel) * 0.01
    xs = np.concatenate([[sentinel, data_lo - 2 * band, data_lo - band, data_lo], xs[keep]])
    alphas = np.concatenate([[0.0, 0.0, a_lo[0], a_lo[0]], alphas[keep]])
    return xs, alphas


def uniform_functions(
    tf: TransferFunction1D, data_lo: float, sentinel: float | None = None
) -> tuple[vtkColorTransferFunction, vtkPiecewiseFunction]:
    """Colour and opacity functions for VTK's uniform-grid mappers (our convention as is)."""
    color = vtkColorTransferFunction()
    color.SetColorSpaceToRGB()
    for x, r, g, b in tf.color_points:
        color.AddRGBPoint(x, r, g, b)
    xs, alphas = tf.opacity_points[:, 0], tf.opacity_points[:, 1]
    if sentinel is not None:
        xs, alphas = _transparent_below(xs, alphas, tf, data_lo, sentinel)
    opacity = vtkPiecewiseFunction()
    for x, a in zip(xs, alphas):
        opacity.AddPoint(x, a)
    return color, opacity


def extinction_nodes(tf: TransferFunction1D) -> NDArray[np.float64]:
    """Node positions at which -ln(1 - a) interpolates linearly within MAX_EXTINCTION_STEP."""
    xs = tf.breakpoints()
    nodes = [xs[:1]]
    for x0, x1 in zip(xs[:-1], xs[1:]):
        y = -np.log1p(-np.minimum(tf.sample(np.array([x0, x1]))[1], MAX_OPACITY))
        pieces = int(min(MAX_SUBDIVISIONS, max(1, np.ceil(abs(y[1] - y[0]) / MAX_EXTINCTION_STEP))))
        nodes.append(np.linspace(x0, x1, pieces + 1)[1:])
    return np.concatenate(nodes)


def unstructured_functions(
    tf: TransferFunction1D, data_lo: float, sentinel: float | None = None
) -> tuple[vtkColorTransferFunction, vtkPiecewiseFunction]:
    """Colour and opacity functions for VTK's unstructured mappers (extinction convention)."""
    xs = extinction_nodes(tf)
    rgb, alphas = tf.sample(xs)
    if sentinel is not None:
        xs2, alphas = _transparent_below(xs, alphas, tf, data_lo, sentinel)
        rgb = np.stack([np.interp(xs2, xs, rgb[:, c]) for c in range(3)], axis=1)
        xs = xs2
    extinction = -np.log1p(-np.minimum(alphas, MAX_OPACITY))
    color = vtkColorTransferFunction()
    color.SetColorSpaceToRGB()
    opacity = vtkPiecewiseFunction()
    for x, (r, g, b), y in zip(xs, rgb, extinction):
        color.AddRGBPoint(x, r, g, b)
        opacity.AddPoint(x, y)
    return color, opacity
