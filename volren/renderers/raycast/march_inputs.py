"""What the `march` kernels read, bundled by what travels together.

Why bundles: the kernels took 15-22 positional parameters (arrays, a float array indexed by
constants), where moving one place still compiled and drew a wrong image. numba types a
`typing.NamedTuple` as a named tuple (arrays allowed as members, fields read by name in nopython
mode, cached kernels keep working while the class is defined at module level), so each bundle
below reaches a kernel as one parameter at no cost per sample. The label and channel bundles are
the shared kernels' (`volren.kernels.label_sample`, `volren.kernels.channel_sample`), re-exported here.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from volren.kernels.mixed_inputs import ChannelClassification, LabelClassification

__all__ = [
    "COUNTS", "TILE", "ChannelClassification", "Classification", "EmptyBricks", "FLAT", "Gradients2D", "IndexRay",
    "LabelClassification", "PixelView", "TRANSPARENT", "Table2D", "gradients", "interval_kinds",
]  # fmt: skip

#: Tiles of TILE x TILE pixels are handed to threads one at a time (neighbouring rays share cache lines).
TILE = 8
#: The columns of a march's counts, per tile or listed pixel: samples taken, distance jumps, segments
#: skipped in empty bricks, rays that became opaque before their last segment.
COUNTS = ("samples", "jumps", "skipped", "terminated")


class PixelView(NamedTuple):
    """One frame's pixel rays, as the kernels unproject them (`march._pixel_ray`)."""

    #: inverse of projection @ view: pixel centres are unprojected at NDC depth -1 and 1
    inverse: NDArray[np.floating[Any]]
    width: int
    height: int
    #: the grid's world origin and spacing (x, y, z): world to index space
    grid_origin: NDArray[np.float64]
    spacing: NDArray[np.float64]
    #: the camera's unit view direction and the far plane's depth from the near plane along it
    view_dir: NDArray[np.float64]
    far_depth: float
    #: each pixel's segment phase in steps (`volren.kernels.sample_placement.pixel_phases`)
    phases: NDArray[np.float64]
    #: (m, 4) half-spaces in index space that rays are clipped to (`volren.kernels.clip_planes`)
    planes: NDArray[np.float64]


class Classification(NamedTuple):
    """How a segment of the step's length gets its colour: post-classified from `post` at its
    middle value, or pre-integrated from `table` by its two end values (Engel et al. 2001)."""

    preintegrated: bool
    #: (n, 4) colour and opacity per step at n values evenly spaced from lo (pre-integrated: only for
    #: cut faces, else unused)
    post: NDArray[np.float64]
    #: (n, n, 4) premultiplied colour and opacity of a step from value i to value j (unused post-classified)
    table: NDArray[np.float32]
    #: the step h (index units along a ray are world units through `PixelView.spacing`)
    step: float
    #: a value s sits at table entry (s - lo) * scale
    lo: float
    scale: float
    #: draw cut faces (`ClipRegion.cap`): `post`'s colour where its opacity is above zero, opaque
    cap: bool


class EmptyBricks(NamedTuple):
    """Empty-space skipping (`occupancy`): `distance[bz, by, bx]` is 0 for a brick to sample, else
    d >= 1 with every brick within Chebyshev distance d - 1 empty too; bricks of `size` cells."""

    distance: NDArray[np.int8]
    size: int


class IndexRay(NamedTuple):
    """One ray in grid-index space, cut into its segments (`volren.kernels.sample_placement`)."""

    ox: float
    oy: float
    oz: float
    dx: float
    dy: float
    dz: float
    #: 1 / d per axis (inf where d is 0)
    ix: float
    iy: float
    iz: float
    #: where the first segment starts, the first and last segments' lengths, how many segments
    t0: float
    first: float
    last: float
    n_segments: int


class Table2D(NamedTuple):
    """A 2D TF as the kernel reads it: `table[j, i]` = (r, g, b, tau per world unit) at value
    lo + i / vscale and gradient magnitude j / gscale."""

    table: NDArray[np.float32]
    lo: float
    vscale: float
    gscale: float
    #: the step h (world units) of the segments
    step: float
    #: per interval [i, i + 1] of table entries along value: TRANSPARENT (no extinction at any
    #: gradient: the gradient is not read), FLAT (the same at every gradient: row 0 is read, the
    #: gradient is not), or else 2 (`interval_kinds`)
    kinds: NDArray[np.int8]


#: `Table2D.kinds`' values (march.c reads the same codes)
TRANSPARENT, FLAT = 0, 1


def interval_kinds(table: NDArray[np.float32]) -> NDArray[np.int8]:
    """`Table2D.kinds` of a table: where a sample's gradient need not be read (most samples of a
    2D TF made from a 1D one, and of the values a TF leaves transparent)."""
    opaque = (table[..., 3] > 0.0).any(axis=0)  # per entry along value: extinction at some gradient
    constant = (table == table[:1]).all(axis=(0, 2))  # per entry: the same at every gradient
    transparent = ~(opaque[:-1] | opaque[1:])
    flat = constant[:-1] & constant[1:]
    return np.where(transparent, TRANSPARENT, np.where(flat, FLAT, 2)).astype(np.int8)


class Gradients2D(NamedTuple):
    """The grid points' gradients (world units), (nz, ny, nx, 3) int16 times `unit`."""

    values: NDArray[np.int16]
    unit: float


def gradients(values: NDArray[Any], spacing: tuple[float, float, float]) -> Gradients2D:
    """The grid points' gradients in world units (central differences, one-sided at the borders:
    the reference's), quantised to int16 over their largest component."""
    data = np.asarray(values, dtype=np.float32)
    parts = [np.gradient(data, axis=axis) / np.float32(spacing[2 - axis]) for axis in (2, 1, 0)]
    finite = [np.where(np.isfinite(p), p, 0.0) for p in parts]
    top = max(float(np.abs(p).max(initial=0.0)) for p in finite) or 1.0
    unit = top / 32767.0
    out = np.empty(data.shape + (3,), np.int16)
    for c, part in enumerate(finite):
        out[..., c] = np.rint(part / unit)
    return Gradients2D(out, unit)
