"""Ray-cell patterns and depth indicators: what each pixel's ray needs to be sampled cell by cell.

Why: the seed precomputes, per view, templates of the rays crossing a cell (its Fig. 2) and keeps
per pixel a *depth indicator*, the position of the ray's next sample, so that the samples of a ray
are evenly spaced across cells visited one at a time. Templates are exact only for a parallel
projection, and approximate there (16^2 template rays, a 4-bit indicator). Here every pixel keeps
its own ray in grid-index coordinates (origin, direction, and the entry `t0`), and the indicator
is the index of its next sample: the ray-cell pattern of a cell is then the exact slab test of each
pixel of its footprint, which is as cheap as a template lookup and exact for parallel and
perspective views alike (each pixel has its own direction).

Sample positions (world length t along the unit ray from its origin on the near plane), exactly a
ray caster's: the ray is clipped to the grid's box and the near and far planes, [t0, t1]; it is cut
into segments of the step h from t0 (the last one shorter, `rem`); sample k sits at
t0 + (k + o) h in its segment, o in [0, 1) the pixel's offset (the last, short segment at the same
fraction o of its length). Offsets: `midpoint` (o = 1/2), `interleaved` (1/4 and 3/4 on a
checkerboard: neighbouring pixels start half a step apart, the seed's Fig. 3d), `random` (seeded).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from volren.model import Camera, UniformVolume

OFFSET_MODES = ("interleaved", "midpoint", "random")


@dataclass
class RayTable:
    """Per pixel (flattened, row 0 at the top): the ray in index space and its samples."""

    origin: NDArray[np.float64]  #: (P, 3) ray origin in grid-index coordinates (x, y, z)
    direction: NDArray[np.float64]  #: (P, 3) index units per world unit along the ray
    world_direction: NDArray[np.float64]  #: (P, 3) unit world direction (shading's view vector)
    t0: NDArray[np.float64]  #: (P,) where sampling starts (world length from the origin)
    count: NDArray[np.int32]  #: (P,) samples of the ray
    full: NDArray[np.int32]  #: (P,) full-length segments (count - full is 0 or 1)
    rem: NDArray[np.float64]  #: (P,) length of the last, short segment (0 when none)
    offset: NDArray[np.float64]  #: (P,) o in [0, 1)


def pixel_offsets(mode: str, width: int, height: int, seed: int) -> NDArray[np.float64]:
    """The offsets o of every pixel for `mode` (see the module docstring)."""
    if mode == "midpoint":
        return np.full(width * height, 0.5)
    if mode == "interleaved":
        jj, ii = np.mgrid[0:height, 0:width]
        return np.where((ii + jj) % 2 == 0, 0.25, 0.75).reshape(-1)
    return np.random.default_rng(seed).random(width * height)


def box_interval(origin: NDArray, direction: NDArray, upper: NDArray) -> tuple[NDArray, NDArray]:
    """Entry and exit t of rays (index space) through the box [0, upper], with the kernels' own
    plane formula (q - o) * (1 / d): the box faces then cut rays exactly where the cells' do."""
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / direction
        ta = (0.0 - origin) * inv
        tb = (upper - origin) * inv
    flat = direction == 0.0
    inside = (origin >= 0.0) & (origin <= upper)
    t_in = np.where(flat, np.where(inside, -np.inf, np.inf), np.minimum(ta, tb)).max(axis=1)
    t_out = np.where(flat, np.where(inside, np.inf, -np.inf), np.maximum(ta, tb)).min(axis=1)
    return t_in, t_out


def ray_table(camera: Camera, volume: UniformVolume, width: int, height: int, h: float,
              offsets: NDArray[np.float64]) -> RayTable:  # fmt: skip
    """Every pixel's ray (through its centre, origin on the near plane) and its samples at step h."""
    origins, directions = camera.pixel_rays(width, height)
    origins = origins.reshape(-1, 3)
    directions = directions.reshape(-1, 3)
    spacing = np.asarray(volume.spacing, dtype=np.float64)
    o = (origins - np.asarray(volume.origin, dtype=np.float64)) / spacing
    d = directions / spacing
    upper = np.asarray(volume.dimensions, dtype=np.float64) - 1.0
    t_in, t_out = box_interval(o, d, upper)
    near, far = camera.clipping_range
    t_far = (far - near) / (directions @ np.asarray(camera.direction, dtype=np.float64))
    t0 = np.maximum(t_in, 0.0)
    t1 = np.minimum(t_out, t_far)
    length = np.where(t1 > t0, t1 - t0, 0.0)
    full = np.floor(length / h)
    rem = length - full * h
    rem = np.where(rem > 1e-9 * h, rem, 0.0)  # a sliver below rounding adds no sample
    count = full + (rem > 0)
    return RayTable(o, d, directions, np.where(length > 0, t0, 0.0), count.astype(np.int32),
                    full.astype(np.int32), rem, np.ascontiguousarray(offsets, dtype=np.float64))  # fmt: skip


def sample_positions(table: RayTable, h: float, pixel: int) -> NDArray[np.float64]:
    """The t of every sample of one pixel's ray (for tests and comparisons)."""
    k = np.arange(int(table.count[pixel]), dtype=np.float64)
    t = table.t0[pixel] + (k + table.offset[pixel]) * h
    if table.count[pixel] > table.full[pixel]:
        t[-1] = table.t0[pixel] + table.full[pixel] * h + table.offset[pixel] * table.rem[pixel]
    return t


def screen_matrix(camera: Camera, volume: UniformVolume, width: int, height: int) -> NDArray[np.float64]:
    """3x4 matrix taking grid-index points (x, y, z, 1) to (U, V, W) with pixel coordinates
    u = U / W, v = V / W (pixel (i, j)'s centre at u = i, v = j, row 0 at the top); W is the
    clip-space w (1 for a parallel view, the depth in front of the eye for a perspective one)."""
    clip = camera.projection_matrix(width / height) @ camera.view_matrix()
    index_to_world = np.eye(4)
    index_to_world[:3, :3] = np.diag(volume.spacing)
    index_to_world[:3, 3] = volume.origin
    m = clip @ index_to_world
    out = np.empty((3, 4))
    out[0] = m[0] * (width / 2.0) + m[3] * ((width - 1) / 2.0)
    out[1] = -m[1] * (height / 2.0) + m[3] * ((height - 1) / 2.0)
    out[2] = m[3]
    return out
