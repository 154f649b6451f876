"""Picking: which point of the volume a pixel shows, with its value and gradient magnitude.

Why: dual-domain interaction (Real-Time Volume Graphics, section 10.6) places a 2D TF widget at the (value, |grad s|)
of a point the person clicks in the rendered image, so the pick must find the point the image
actually shows there under the current TF, with the renderers' own reconstruction.

The ray is the renderers' ray through the centre of pixel (x, y) (row 0 at the top), starting on
the near plane and ending on the far plane (`Camera.pixel_rays`, `kernels.tet_projection.ray_far`). It is
sampled every `STEP_FRACTION` characteristic lengths (smallest voxel spacing or mean tet edge):

- uniform grids: the trilinear interpolant of the values, and the gradient the renderers shade
  with (central differences at the grid points in world units, one-sided at the borders,
  interpolated trilinearly like the values); a cell with a non-finite corner is no data;
- tetrahedral meshes: the renderers' exact ray-tetrahedron clipping (`kernels.tet_clipping`
  on the candidates of `kernels.tet_projection.projected_boxes`), linear values and the constant gradient in each
  tet; gaps of a non-convex mesh are no data.

Each piece of the ray gets the TF's extinction at its midpoint (1D or 2D TF, DESIGN.md's optical
model), and the picked point is, in this order of preference:

1. "opacity": where the accumulated opacity 1 - T reaches `OPACITY_THRESHOLD` (0.5), solved
   exactly inside the piece (constant extinction there): the depth a person reads as the surface;
2. "strongest": if it never does, the midpoint of the piece that adds the most to the pixel
   (T alpha): the most visible thing along a mostly transparent ray;
3. "first": if nothing along the ray is visible, the first sample inside the data, so that a
   click on invisible material still tells the value there (and a new widget makes it visible).

`pick` returns None only when the ray meets no data (outside the image, misses the volume, or
passes only through gaps and non-finite cells).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError
from volren.kernels.box_clipping import clip_box
from volren.kernels.tet_clipping import clip_tet
from volren.kernels.tet_projection import projected_boxes, ray_far
from volren.model.camera import Camera
from volren.model.tet_mesh import prepare_mesh
from volren.model.transfer_function_2d import TransferFunction
from volren.model.volume import TetVolume, UniformVolume, Volume

#: Sample spacing along the ray, in characteristic lengths (smallest voxel spacing, mean tet edge).
STEP_FRACTION = 0.25
#: The accumulated opacity at which a ray counts as having reached the surface it shows.
OPACITY_THRESHOLD = 0.5

Rule = Literal["opacity", "strongest", "first"]


@dataclass(frozen=True)
class PickResult:
    """The picked point (world units), the data there, and which rule chose it (module docstring)."""

    position: tuple[float, float, float]
    value: float
    gradient_magnitude: float
    #: Distance along the ray from its start on the near plane.
    depth: float
    #: Accumulated opacity 1 - T at the point.
    opacity: float
    rule: Rule


def pixel_ray(camera: Camera, x: float, y: float, width: int, height: int) -> tuple[NDArray, NDArray]:
    """Origin (on the near plane) and unit direction of the ray through the centre of pixel (x, y),
    the ray `Camera.pixel_rays` gives there (to rounding)."""
    return camera.rays(width, height, x, y)


# ----------------------------------------------------------------------------- uniform grids
def _grid_gradient(
    values: NDArray, spacing: tuple[float, float, float], k: NDArray, j: NDArray, i: NDArray
) -> NDArray:
    """(n, 3) gradient at grid points (k, j, i): central differences, one-sided at the borders."""
    out = np.empty(k.shape + (3,))
    index = [k, j, i]
    for axis, comp in ((2, 0), (1, 1), (0, 2)):
        n = values.shape[axis]
        lo = np.maximum(index[axis] - 1, 0)
        hi = np.minimum(index[axis] + 1, n - 1)
        a, b = list(index), list(index)
        a[axis], b[axis] = hi, lo
        diff = values[tuple(a)].astype(np.float64) - values[tuple(b)].astype(np.float64)
        out[..., comp] = diff / ((hi - lo) * spacing[comp])
    return out


def sample_grid(volume: UniformVolume, points: NDArray) -> tuple[NDArray, NDArray]:
    """Trilinear value (n,) and gradient (n, 3) at world points inside the grid's box; NaN in
    cells with a non-finite corner (no data there)."""
    p = np.atleast_2d(np.asarray(points, dtype=np.float64))
    dims = np.asarray(volume.dimensions)
    u = (p - np.asarray(volume.origin)) / np.asarray(volume.spacing)
    cell = np.clip(np.floor(u).astype(np.int64), 0, dims - 2)
    f = np.clip(u - cell, 0.0, 1.0)
    value = np.zeros(len(p))
    grad = np.zeros((len(p), 3))
    for dz in (0, 1):
        for dy in (0, 1):
            for dx in (0, 1):
                w = (
                    (f[:, 0] if dx else 1.0 - f[:, 0])
                    * (f[:, 1] if dy else 1.0 - f[:, 1])
                    * (f[:, 2] if dz else 1.0 - f[:, 2])
                )
                i, j, k = cell[:, 0] + dx, cell[:, 1] + dy, cell[:, 2] + dz
                corner = volume.values[k, j, i].astype(np.float64)
                value += w * corner
                value[~np.isfinite(corner)] = np.nan  # 0 * NaN would hide it where w == 0
                grad += w[:, None] * _grid_gradient(volume.values, volume.spacing, k, j, i)
    grad[~np.isfinite(value)] = np.nan
    return value, grad


def _uniform_samples(
    volume: UniformVolume, origin: NDArray, direction: NDArray, t_far: float, step: float
) -> tuple[NDArray, NDArray, NDArray, NDArray] | None:
    """Pieces of the ray inside the box: starts, lengths, midpoint values and gradient magnitudes."""
    b = np.asarray(volume.bounds, dtype=np.float64)
    t0, t1 = clip_box(
        *origin, *direction, np.ascontiguousarray(b[0::2]), np.ascontiguousarray(b[1::2]), 0.0, t_far
    )
    if not t1 > t0:
        return None
    n = max(1, math.ceil((t1 - t0) / step))
    starts = t0 + (t1 - t0) * np.arange(n) / n
    lengths = np.full(n, (t1 - t0) / n)
    value, grad = sample_grid(volume, origin + (starts + 0.5 * lengths)[:, None] * direction)
    return starts, lengths, value, np.linalg.norm(grad, axis=1)


# ------------------------------------------------------------------------ tetrahedral meshes
def _tet_intervals(
    volume: TetVolume,
    camera: Camera,
    x: int,
    y: int,
    width: int,
    height: int,
    origin: NDArray,
    direction: NDArray,
    t_far: float,
) -> NDArray:
    """(entry, exit, value at entry, slope along the ray, |grad s|) of the tets the ray crosses, by entry."""
    mesh = prepare_mesh(volume)  # cached by content, shared with the renderers
    p = mesh.planes
    normals, anchors, sigma, tvals, grads = p.normals, p.anchors, p.sigma, p.values, p.gradients
    boxes = projected_boxes(camera, width, height, mesh.points, mesh.tets, p.usable)
    candidates = np.flatnonzero(
        (boxes[:, 0] <= x) & (x <= boxes[:, 1]) & (boxes[:, 2] <= y) & (y <= boxes[:, 3])
    )
    rows = []
    for t in candidates:
        hit, ta, tb, s0 = clip_tet(int(t), *origin, *direction, t_far, normals, anchors, sigma, tvals)
        if hit:
            rows.append((ta, tb, s0, float(grads[t] @ direction), float(np.linalg.norm(grads[t]))))
    rows.sort(key=lambda r: r[0])
    return np.asarray(rows, dtype=np.float64).reshape(-1, 5)


def _tet_samples(intervals: NDArray, step: float) -> tuple[NDArray, NDArray, NDArray, NDArray, NDArray]:
    """Pieces of every interval (at most `step` long): starts, lengths, midpoint values, |grad s|,
    and the interval each piece lies in."""
    ta, tb = intervals[:, 0], intervals[:, 1]
    counts = np.maximum(1, np.ceil((tb - ta) / step)).astype(np.int64)
    owner = np.repeat(np.arange(len(intervals)), counts)
    first = np.cumsum(counts) - counts
    index = np.arange(owner.size) - first[owner]
    lengths = (tb - ta)[owner] / counts[owner]
    starts = ta[owner] + index * lengths
    mids = starts + 0.5 * lengths
    values = intervals[owner, 2] + intervals[owner, 3] * (mids - ta[owner])
    return starts, lengths, values, intervals[owner, 4], owner


# --------------------------------------------------------------------------------- picking
def _extinction(tf: TransferFunction, values: NDArray, gradients: NDArray) -> NDArray:
    if tf.dims == 2:
        return tf.extinction(values, gradients)  # type: ignore[call-arg]
    return tf.extinction(values)  # type: ignore[call-arg]


def _choose(
    starts: NDArray, lengths: NDArray, tau: NDArray, inside: NDArray
) -> tuple[float, float, Rule] | None:
    """(depth, accumulated opacity, rule) of the picked point among the ray's pieces."""
    tau = np.where(inside, tau, 0.0)
    depth = tau * lengths
    after = np.exp(-np.cumsum(depth))
    before = np.concatenate([[1.0], after[:-1]])
    reached = np.flatnonzero(1.0 - after >= OPACITY_THRESHOLD)
    if reached.size:
        n = int(reached[0])
        keep = 1.0 - OPACITY_THRESHOLD
        into = math.log(before[n] / keep) / tau[n] if before[n] > keep else 0.0
        return float(starts[n] + min(into, lengths[n])), OPACITY_THRESHOLD, "opacity"
    contribution = before * -np.expm1(-depth)
    if contribution.max(initial=0.0) > 0.0:
        n = int(np.argmax(contribution))
        return float(starts[n] + 0.5 * lengths[n]), float(1.0 - after[n]), "strongest"
    first = np.flatnonzero(inside)
    if first.size == 0:
        return None
    n = int(first[0])
    return float(starts[n] + 0.5 * lengths[n]), 0.0, "first"


def pick(
    volume: Volume, tf: TransferFunction, camera: Camera, x: int, y: int, width: int, height: int
) -> PickResult | None:
    """The point pixel (x, y) of a width x height image shows (see the module docstring), or None."""
    if width < 1 or height < 1:
        raise VolrenError(f"picking needs an image of at least 1 x 1 pixels, got {width} x {height}")
    if not (0 <= x < width and 0 <= y < height):
        return None
    origin, direction = pixel_ray(camera, x, y, width, height)
    t_far = float(ray_far(camera, direction[None, :])[0])
    step = STEP_FRACTION * volume.characteristic_length
    if isinstance(volume, UniformVolume):
        samples = _uniform_samples(volume, origin, direction, t_far, step)
        if samples is None:
            return None
        starts, lengths, values, mags = samples
        owner = None
        intervals = None
    else:
        intervals = _tet_intervals(volume, camera, int(x), int(y), width, height, origin, direction, t_far)
        if len(intervals) == 0:
            return None
        starts, lengths, values, mags, owner = _tet_samples(intervals, step)
    inside = np.isfinite(values) & np.isfinite(mags)
    tau = _extinction(tf, np.where(inside, values, 0.0), np.where(inside, mags, 0.0))
    chosen = _choose(starts, lengths, tau, inside)
    if chosen is None:
        return None
    depth, opacity, rule = chosen
    point = origin + depth * direction
    if isinstance(volume, UniformVolume):
        value, grad = sample_grid(volume, point[None, :])
        value_at, magnitude = float(value[0]), float(np.linalg.norm(grad[0]))
        if not math.isfinite(value_at):  # the point sits on the edge of a no-data cell
            n = int(np.searchsorted(starts, depth, side="right") - 1)
            value_at, magnitude = float(values[n]), float(mags[n])
    else:
        assert intervals is not None and owner is not None
        n = int(np.searchsorted(starts, depth, side="right") - 1)
        row = intervals[owner[n]]
        value_at, magnitude = float(row[2] + row[3] * (depth - row[0])), float(row[4])
    return PickResult(
        position=(float(point[0]), float(point[1]), float(point[2])),
        value=value_at,
        gradient_magnitude=magnitude,
        depth=depth,
        opacity=opacity,
        rule=rule,
    )
