"""Closed forms of the optical model that need no reference run (numpy, float64).

Each function computes, from the formulas of the renderer contract alone, what an exact renderer
draws for one of the kit's scenes: path lengths through a box, the emission of a linear ramp, the
projection of one point. None of them calls a renderer.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from volren.model.camera import Camera
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import UniformVolume

#: The contract's opacity clamp: a(s) is used as min(a(s), MAX_OPACITY).
MAX_OPACITY = 1.0 - 1e-6


def kept_interval(
    origins: NDArray[np.float64],
    directions: NDArray[np.float64],
    far: NDArray[np.float64],
    bounds: Sequence[float],
    half_spaces: NDArray[np.float64] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """(start, end, box start) per ray (origins and unit directions (..., 3), far-plane parameters
    (...)): the ray parameters of the part inside the box, from the near plane (t = 0) to `far`,
    on the kept side (a x + b y + c z + d >= 0) of every row of `half_spaces` ((m, 4), world); and
    where it enters the box alone. An empty part has end <= start."""
    lo = np.asarray(bounds[0::2], dtype=np.float64)
    hi = np.asarray(bounds[1::2], dtype=np.float64)
    inside = (origins >= lo) & (origins <= hi)
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = (lo - origins) / directions
        t2 = (hi - origins) / directions
    parallel_to_slab = directions == 0
    t_min = np.where(parallel_to_slab, np.where(inside, -np.inf, np.inf), np.minimum(t1, t2))
    t_max = np.where(parallel_to_slab, np.where(inside, np.inf, -np.inf), np.maximum(t1, t2))
    box_start = np.maximum(t_min.max(axis=-1), 0.0)
    start = box_start.copy()
    end = np.minimum(t_max.min(axis=-1), far)
    for a, b, c, d in np.zeros((0, 4)) if half_spaces is None else np.asarray(half_spaces, np.float64):
        at_origin = origins @ (a, b, c) + d
        rate = directions @ (a, b, c)
        with np.errstate(divide="ignore", invalid="ignore"):
            crossing = -at_origin / rate
        start = np.where(rate > 0, np.maximum(start, crossing), start)
        end = np.where(rate < 0, np.minimum(end, crossing), end)
        end = np.where((rate == 0) & (at_origin < 0), -np.inf, end)
    return start, end, box_start


def pixel_kept_intervals(
    camera: Camera,
    width: int,
    height: int,
    bounds: Sequence[float],
    half_spaces: NDArray[np.float64] | None = None,
) -> tuple[
    NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]
]:
    """(origins, directions, start, end, box start): `kept_interval` of every pixel-centre ray of
    `camera` (origins on the near plane, unit directions, (H, W, 3)), the far plane included."""
    origins, directions = camera.pixel_rays(width, height)
    near, far = camera.clipping_range
    start, end, box_start = kept_interval(
        origins, directions, (far - near) / (directions @ camera.direction), bounds, half_spaces
    )
    return origins, directions, start, end, box_start


def at_an_edge(mask: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """Pixels (not on the image's border) with a 4-neighbour of another `mask` value: where a ray
    grazing the edge of a region may fall either way in float precision."""
    differs = np.any([np.roll(mask, s, axis=a) != mask for a in (0, 1) for s in (1, -1)], axis=0)
    edge = np.zeros_like(mask)
    edge[1:-1, 1:-1] = differs[1:-1, 1:-1]
    return edge


def box_path_lengths(
    camera: Camera,
    width: int,
    height: int,
    bounds: Sequence[float],
    half_spaces: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """Length (H, W) of each pixel-centre ray inside the box, between the near and far planes, and
    on the kept side of every row of `half_spaces` (`kept_interval`)."""
    _, _, start, end, _ = pixel_kept_intervals(camera, width, height, bounds, half_spaces)
    return np.maximum(end - start, 0.0)


def entered_through_a_plane(
    camera: Camera, width: int, height: int, bounds: Sequence[float], half_spaces: NDArray[np.float64]
) -> tuple[NDArray[np.bool_], NDArray[np.float64]]:
    """(H, W) whether each pixel-centre ray enters the part of the box kept by `half_spaces`
    through one of them (where a cut face is drawn) rather than through the box or the near plane,
    and (H, W, 3) the entry points."""
    origins, directions, start, end, box_start = pixel_kept_intervals(
        camera, width, height, bounds, half_spaces
    )
    through = (start > box_start) & (end > start)
    return through, origins + start[..., None] * directions


def homogeneous_image(
    lengths: NDArray, rgb: Sequence[float], opacity: float, unit_distance: float
) -> NDArray[np.float64]:
    """Premultiplied RGBA of a constant medium: alpha = 1 - (1 - a)^(L / d_u), colour = c alpha."""
    a = min(float(opacity), MAX_OPACITY)
    alpha = 1.0 - (1.0 - a) ** (np.asarray(lengths, dtype=np.float64) / unit_distance)
    return np.concatenate([alpha[..., None] * np.asarray(rgb, dtype=np.float64), alpha[..., None]], axis=-1)


def linear_colour_emission(
    colour_points: Sequence[tuple[float, float]], extinction: float, entry: float, exit_: float
) -> tuple[float, float]:
    """(premultiplied colour, alpha) of one channel along a ray on which s runs linearly from
    `entry` to `exit_` at unit speed, with constant extinction and the colour piecewise linear
    through `colour_points` ((s, c), constant beyond the ends).

    Per linear piece of length L starting at colour c0 with slope g per unit length:
    C = T (c0 (1 - e) + g ((1 - e) / tau - L e)), e = exp(-tau L), T the transmittance before it."""
    xs = np.asarray([p[0] for p in colour_points], dtype=np.float64)
    cs = np.asarray([p[1] for p in colour_points], dtype=np.float64)
    lo, hi = min(entry, exit_), max(entry, exit_)
    knots = np.unique(np.clip(np.concatenate([xs, [entry, exit_]]), lo, hi))
    if exit_ < entry:
        knots = knots[::-1]
    colour, transmittance = 0.0, 1.0
    for a, b in zip(knots[:-1], knots[1:], strict=True):
        length = abs(b - a)
        c0 = float(np.interp(a, xs, cs))
        slope = (float(np.interp(b, xs, cs)) - c0) / length
        e = math.exp(-extinction * length)
        colour += transmittance * (c0 * (1 - e) + slope * ((1 - e) / extinction - length * e))
        transmittance *= e
    return colour, 1.0 - transmittance


def projection_rgba(tf: TransferFunction1D, values: NDArray) -> NDArray[np.float64]:
    """What maximum / minimum / average projection draws for the projected values: (c(v) a(v), a(v)),
    the TF's opacity without length correction."""
    rgb, alpha = tf.sample(values)
    return np.concatenate([rgb * alpha[..., None], alpha[..., None]], axis=-1)


def column_projection(values_zyx: NDArray, mode: str) -> NDArray[np.float64]:
    """Maximum, minimum or average along z of a trilinear (or Kuhn-linear) field sampled on a
    lattice, along the lattice's z columns: there the field is piecewise linear between the
    samples, so the extremes are samples and the mean is the trapezoid rule. Result (ny, nx)."""
    v = np.asarray(values_zyx, dtype=np.float64)
    if mode == "maximum":
        return v.max(axis=0)
    if mode == "minimum":
        return v.min(axis=0)
    if mode == "average":
        return (v.sum(axis=0) - 0.5 * (v[0] + v[-1])) / (v.shape[0] - 1)
    raise ValueError(f"no column projection for {mode}")


def pixel_of(camera: Camera, width: int, height: int, point: Sequence[float]) -> tuple[float, float]:
    """Where the camera contract puts a world point: (column, row) in pixels, in the frame where
    pixel (i, j) has its centre at (i, j) and row 0 is the top."""
    clip = (
        camera.projection_matrix(width / height)
        @ camera.view_matrix()
        @ np.append(np.asarray(point, float), 1.0)
    )
    ndc = clip[:3] / clip[3]
    return (ndc[0] + 1.0) / 2.0 * width - 0.5, (1.0 - ndc[1]) / 2.0 * height - 0.5


def weighted_centroid(weights: NDArray) -> tuple[float, float]:
    """(column, row) centroid of a non-negative (H, W) image, in the same pixel frame as `pixel_of`."""
    w = np.asarray(weights, dtype=np.float64)
    total = w.sum()
    if not total > 0:
        return math.nan, math.nan
    rows, cols = np.indices(w.shape)
    return float((w * cols).sum() / total), float((w * rows).sum() / total)


def midpoint_march(volume: UniformVolume, tf: TransferFunction1D, camera: Camera, w: int, h_px: int, step: float,
                offsets: np.ndarray) -> np.ndarray:  # fmt: skip
    """A plain ray caster, pixel by pixel in float64 (the samples the CPU ray casters take): every pixel ray clipped to the box and the clipping planes, cut into
    segments of the step at (phase + j) steps from its origin (the first and last shorter), each sampled
    at its middle, trilinear, post-classified with the opacity corrected to the segment's length,
    front to back."""
    origins, dirs = camera.pixel_rays(w, h_px)
    origins, dirs = origins.reshape(-1, 3), dirs.reshape(-1, 3)
    b = np.asarray(volume.bounds)
    lo, hi = b[0::2], b[1::2]
    with np.errstate(divide="ignore", invalid="ignore"):
        ta, tb = (lo - origins) / dirs, (hi - origins) / dirs
    flat = dirs == 0
    inside = (origins >= lo) & (origins <= hi)
    t_in = np.where(flat, np.where(inside, -np.inf, np.inf), np.minimum(ta, tb)).max(axis=1)
    t_out = np.where(flat, np.where(inside, np.inf, -np.inf), np.maximum(ta, tb)).min(axis=1)
    near, far = camera.clipping_range
    t0 = np.maximum(t_in, 0.0)
    t1 = np.minimum(t_out, (far - near) / (dirs @ camera.direction))
    hstep = step * volume.characteristic_length
    values = volume.values.astype(np.float64)
    dims = np.asarray(volume.dimensions)
    out = np.zeros((len(origins), 4))
    for p in range(len(origins)):
        length = t1[p] - t0[p]
        if not length > 0:
            continue
        j0 = np.floor(t0[p] / hstep)
        cuts = (offsets[p] + j0 + np.arange(0, int(length / hstep) + 3)) * hstep
        cuts = cuts[(cuts > t0[p] + 1e-9 * hstep) & (cuts < t1[p] - 1e-9 * hstep)]
        ends = np.concatenate([[t0[p]], cuts, [t1[p]]])
        seg = [((a + b) / 2, b - a) for a, b in zip(ends[:-1], ends[1:], strict=True)]
        tr = 1.0
        for t, seg_len in seg:
            idx = (origins[p] + t * dirs[p] - np.asarray(volume.origin)) / np.asarray(volume.spacing)
            base = np.clip(np.floor(idx), 0, dims - 2).astype(int)
            f = np.clip(idx - base, 0, 1)
            s = 0.0
            for c in range(8):
                d = np.array([c & 1, (c >> 1) & 1, c >> 2])
                wgt = np.prod(np.where(d == 1, f, 1 - f))
                s += wgt * values[base[2] + d[2], base[1] + d[1], base[0] + d[0]]
            rgb, a = tf.sample(s)
            alpha = 1 - (1 - min(float(a), 1 - 1e-6)) ** (seg_len / tf.opacity_unit_distance)
            out[p, :3] += tr * alpha * rgb
            out[p, 3] += tr * alpha
            tr *= 1 - alpha
    return out.reshape(h_px, w, 4)


def tent_sheet_alpha(tf: TransferFunction1D, thickness: float, cos_angle: float) -> float:
    """Opacity of a ray crossing a sheet whose value falls linearly from 1 on its mid-plane to 0 at
    `thickness` / 2 either side (one layer of lattice points at 1, interpolated trilinearly or per
    tetrahedron), at `cos_angle` to the sheet's normal: 1 - exp(-(thickness / cos) * mean over
    [0, 1] of the extinction tau(v)), the mean taken in float64 over 400,001 points."""
    v = np.linspace(0.0, 1.0, 400_001)
    _, alpha = tf.sample(v)
    tau = -np.log1p(-np.minimum(np.asarray(alpha, np.float64), 1.0 - 1e-6)) / tf.opacity_unit_distance
    return float(1.0 - np.exp(-thickness / abs(cos_angle) * np.trapezoid(tau, v)))
