"""Our transfer function expressed in VTK's terms, so that VTK draws DESIGN.md's optical model.

Uniform mappers (smart, GPU ray cast, fixed point) share our convention: the opacity a of a
slab `ScalarOpacityUnitDistance` thick, corrected per sample as 1 - (1 - a)^(h / d). They get the
control points as they are.

The unstructured mappers (ray cast, projected tetrahedra, ZSweep) differ twice (measured, see
../shared/scenes/README.md):
- they read the opacity value y as an extinction y / d per unit length, where our model has
  -ln(1 - a) / d; so we hand them y = -ln(1 - min(a, 1 - 1e-6)), and since that is not linear in
  s where a is, we add nodes inside each interval where the opacity changes. Their spacing
  follows the curvature of y(a) = -ln(1 - a): y'' = 1 / (1 - a)^2, so with 1 - a shrinking by a
  factor q = 1 / (1 + sqrt(8 eps)) from node to node, linear interpolation of y between nodes is
  within eps of the exact curve (eps = MAX_EXTINCTION_ERROR). That takes 9 nodes for a ramp to
  0.7 and 100 for a ramp to 1, where spacing them evenly in s would take hundreds: VTK's
  integrators pay for every node a ray crosses;
- they read the opacity function only at colour nodes, so every node carries both a colour and
  an opacity.

Non-finite values (the contract: a cell with a non-finite corner is transparent, the rest is drawn
as usual). Tetrahedra with such a corner are left out of the mesh VTK gets (`convert`), which is
the rule exactly. On grids a cell cannot be left out, and trilinear interpolation between any
stand-in value and its finite neighbours gives values the TF draws: a sentinel one data range
below the finite minimum, made transparent there, still let half of many such cells through
(10 % scattered NaN points: 1.66x the reference's opacity). So on the GPU ray caster (composite)
the grid also carries a point array `finite` (1 at finite points, 0 elsewhere) that VTK
interpolates like the scalars and uses as the second axis of a 2D TF (`masked_table`): the TF
itself in the top row, where `finite` interpolates to 1 (all eight corners finite), and nothing
below it. Only a sliver of each such cell, where the non-finite corner's weight is under about
1.5 / MASK_ROWS, keeps some opacity. VTK applies no opacity correction to a 2D TF, so the table
holds the per-sample opacity 1 - (1 - a)^(h / d) for the mapper's sample distance h. Mappers
without 2D TFs (fixed point, smart, the projection blend modes) keep the sentinel alone, and
with it the approximation.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from volren.model.transfer_function import MAX_OPACITY, TransferFunction1D
from volren.renderers.vtk_mappers._vtk import (
    numpy_to_vtk,
    vtkColorTransferFunction,
    vtkImageData,
    vtkPiecewiseFunction,
)

#: Largest error of -ln(1 - a) between the nodes handed to the unstructured mappers.
MAX_EXTINCTION_ERROR = 0.002
MAX_SUBDIVISIONS = 256

#: Size of the 2D TF that hides grid cells with a non-finite corner: columns over the scalar range
#: (sentinel to maximum, so half of them cover the data), rows over `finite` from 0 to 1; 16 MiB.
#: Measured on 10 % scattered NaN points, opacity against the reference: 1.09 with 64 rows, 1.03
#: with 256, 1.007 with 1024.
MASK_COLUMNS = 2048
MASK_ROWS = 512

#: VTK's mappers scale the scalars by their span in float32 and drew blank frames where that failed
#: (measured, VTK 9.x on llvmpipe, default TF on float32 data out to +-3.4e38): the GPU ray caster
#: from a span of about 9e37, where 1 / span is no longer a normal float32, the fixed-point ray
#: caster where the span overflows float32. So scalars of larger magnitude go to VTK times a power
#: of two that keeps their span, sentinel included, within 2^MAX_SPAN_EXPONENT: such a factor is
#: exact, and the TF's nodes get it too.
MAX_SPAN_EXPONENT = 100


def vtk_scale(data_range: tuple[float, float]) -> float:
    """1, or the power of two that brings the finite data within +-2^(MAX_SPAN_EXPONENT - 3): then
    every scalar VTK gets, the sentinel one data range below them included, spans at most
    2^MAX_SPAN_EXPONENT. Scaled float32 data stays exact down to magnitudes of about 2^-95."""
    limit = MAX_SPAN_EXPONENT - 3
    magnitude = max(abs(data_range[0]), abs(data_range[1]))
    if magnitude <= 2.0**limit:
        return 1.0
    return 2.0 ** (limit - math.ceil(math.log2(magnitude)))


def scaled_values(values: NDArray, scale: float) -> NDArray:
    """`values` times `scale` in their own dtype (exact for a power of two; no copy for 1)."""
    return values if scale == 1.0 else values * values.dtype.type(scale)


def scaled_tf(tf: TransferFunction1D, scale: float) -> TransferFunction1D:
    """`tf` over values times `scale`, for scalars that went to VTK through `scaled_values`."""
    if scale == 1.0:
        return tf
    color, opacity = tf.color_points, tf.opacity_points
    color[:, 0] *= scale
    opacity[:, 0] *= scale
    return TransferFunction1D(color, opacity, tf.opacity_unit_distance)


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


def _functions(
    color_x: NDArray, rgb: NDArray, opacity_x: NDArray, opacity_y: NDArray
) -> tuple[vtkColorTransferFunction, vtkPiecewiseFunction]:
    """VTK functions with these nodes, keeping two nodes at one x (a step in the TF stays a step).

    The nodes go in as whole arrays: VTK sorts its nodes after every AddPoint / AddRGBPoint, which
    made a TF with 20,000 points take 6 s to hand over; these bulk calls sort once."""
    color = vtkColorTransferFunction()
    color.SetColorSpaceToRGB()
    color.AllowDuplicateScalarsOn()
    x = np.ascontiguousarray(color_x, dtype=np.float64)
    color.AddRGBPoints(
        numpy_to_vtk(x, deep=1), numpy_to_vtk(np.ascontiguousarray(rgb, dtype=np.float64), deep=1)
    )
    opacity = vtkPiecewiseFunction()
    opacity.AllowDuplicateScalarsOn()
    pairs = np.ascontiguousarray(np.stack([opacity_x, opacity_y], axis=1), dtype=np.float64).ravel()
    opacity.FillFromDataPointer(len(opacity_x), pairs)  # type: ignore[arg-type]  # VTK reads the buffer
    return color, opacity


def uniform_functions(
    tf: TransferFunction1D, data_lo: float, sentinel: float | None = None
) -> tuple[vtkColorTransferFunction, vtkPiecewiseFunction]:
    """Colour and opacity functions for VTK's uniform-grid mappers (our convention as is)."""
    xs, alphas = tf.opacity_points[:, 0], tf.opacity_points[:, 1]
    if sentinel is not None:
        xs, alphas = _transparent_below(xs, alphas, tf, data_lo, sentinel)
    return _functions(tf.color_points[:, 0], tf.color_points[:, 1:4], xs, alphas)


def _opacity_steps(a0: float, a1: float) -> NDArray[np.float64]:
    """Opacities strictly between a0 and a1 (ascending where a0 < a1) where linear interpolation
    of -ln(1 - min(a, MAX_OPACITY)) stays within MAX_EXTINCTION_ERROR of the curve."""
    lo, hi = sorted((min(a0, MAX_OPACITY), min(a1, MAX_OPACITY)))
    shrink = 1.0 / (1.0 + np.sqrt(8.0 * MAX_EXTINCTION_ERROR))
    count = np.log((1.0 - hi) / (1.0 - lo)) / np.log(shrink) if hi > lo else 0.0
    k = np.arange(1, min(int(np.ceil(count)), MAX_SUBDIVISIONS))
    steps = 1.0 - (1.0 - lo) * shrink**k
    if min(a0, a1) < MAX_OPACITY < max(a0, a1):  # the kink where the clamp starts: -ln(1 - a) flat past it
        steps = np.append(steps, MAX_OPACITY)
    return steps if a1 >= a0 else steps[::-1]


def _one_sided(x: NDArray, xp: NDArray, fp: NDArray, side: str) -> NDArray:
    """Piecewise-linear fp(xp) at x, taking the left or right limit where xp repeats (a step)."""
    if side == "right":
        return np.interp(x, xp, fp)
    return np.interp(-x, -xp[::-1], fp[::-1])


def _limits(tf: TransferFunction1D, xs: NDArray, side: str) -> NDArray:
    """(n, 4) [r, g, b, a] of the TF just left or right of each x."""
    c, o = tf.color_points, tf.opacity_points
    rgb = [_one_sided(xs, c[:, 0], c[:, k], side) for k in (1, 2, 3)]
    return np.stack(rgb + [_one_sided(xs, o[:, 0], o[:, 1], side)], axis=1)


def extinction_nodes(tf: TransferFunction1D) -> tuple[NDArray, NDArray]:
    """Node positions (ascending; repeated at steps) and [r, g, b, a] there: the TF's breakpoints
    plus the nodes each opacity ramp needs (see _opacity_steps)."""
    xs = tf.breakpoints()
    left, right = _limits(tf, xs, "left"), _limits(tf, xs, "right")
    out_x: list[float] = []
    out_v: list[NDArray] = []
    for i, x in enumerate(xs):
        if i > 0:  # the ramp from the previous breakpoint's right value to this one's left value
            x0, v0, v1 = xs[i - 1], right[i - 1], left[i]
            for a in _opacity_steps(v0[3], v1[3]):
                t = (a - v0[3]) / (v1[3] - v0[3])
                out_x.append(x0 + t * (x - x0))
                out_v.append(v0 + t * (v1 - v0))
        out_x.append(x)
        out_v.append(left[i])
        if not np.array_equal(left[i], right[i]):
            out_x.append(x)
            out_v.append(right[i])
    return np.array(out_x), np.array(out_v)


def unstructured_functions(
    tf: TransferFunction1D, data_lo: float, sentinel: float | None = None
) -> tuple[vtkColorTransferFunction, vtkPiecewiseFunction]:
    """Colour and opacity functions for VTK's unstructured mappers (extinction convention)."""
    xs, values = extinction_nodes(tf)
    rgb, alphas = values[:, :3], values[:, 3]
    if sentinel is not None:
        xs2, alphas = _transparent_below(xs, alphas, tf, data_lo, sentinel)
        rgb = np.stack([np.interp(xs2, xs, rgb[:, c]) for c in range(3)], axis=1)
        xs = xs2
    extinction = -np.log1p(-np.minimum(alphas, MAX_OPACITY))
    return _functions(xs, rgb, xs, extinction)


def masked_table(
    tf: TransferFunction1D, scalar_range: tuple[float, float], sample_distance: float
) -> NDArray:
    """(MASK_ROWS, MASK_COLUMNS, 4) float32 RGBA of the 2D TF over (value, finite): our TF sampled at
    the texel centres of the scalar range in the top row, with the opacity of one sample step
    `sample_distance` long; zero in every other row (module docstring)."""
    lo, hi = scalar_range
    xs = lo + (np.arange(MASK_COLUMNS) + 0.5) / MASK_COLUMNS * (hi - lo)
    rgb, alpha = tf.sample(xs)
    exponent = sample_distance / tf.opacity_unit_distance
    table = np.zeros((MASK_ROWS, MASK_COLUMNS, 4), dtype=np.float32)
    table[-1, :, :3] = rgb
    table[-1, :, 3] = 1.0 - (1.0 - np.minimum(alpha, MAX_OPACITY)) ** exponent
    return table


def masked_function(
    tf: TransferFunction1D, scalar_range: tuple[float, float], sample_distance: float
) -> vtkImageData:
    """`masked_table` as the vtkImageData that vtkVolumeProperty.SetTransferFunction2D takes."""
    table = masked_table(tf, scalar_range, sample_distance)
    image = vtkImageData()
    image.SetDimensions(MASK_COLUMNS, MASK_ROWS, 1)
    image.GetPointData().SetScalars(numpy_to_vtk(table.reshape(-1, 4), deep=1))
    return image


def per_sample_functions(
    tf: TransferFunction1D, sample_distance: float, data_lo: float, sentinel: float | None = None
) -> tuple[vtkColorTransferFunction, vtkPiecewiseFunction]:
    """Colour and opacity functions holding the opacity of one sample `sample_distance` long,
    1 - (1 - a)^(h / d): for VTK's label-map TFs, which its GPU ray caster reads without opacity
    correction (measured on the kit's label scene: RMSE to `reference` 0.093, 0.146, 0.179 at steps
    0.5, 0.25, 0.125 as given; 0.030, 0.016, 0.010 with this). The nodes are `extinction_nodes`, where
    -ln(1 - a) is nearly linear, so the per-sample opacity between them is nearly exact too."""
    xs, values = extinction_nodes(tf)
    rgb, alphas = values[:, :3], values[:, 3]
    if sentinel is not None:
        xs2, alphas = _transparent_below(xs, alphas, tf, data_lo, sentinel)
        rgb = np.stack([np.interp(xs2, xs, rgb[:, c]) for c in range(3)], axis=1)
        xs = xs2
    exponent = sample_distance / tf.opacity_unit_distance
    per_sample = 1.0 - (1.0 - np.minimum(alphas, MAX_OPACITY)) ** exponent
    return _functions(xs, rgb, xs, per_sample)
