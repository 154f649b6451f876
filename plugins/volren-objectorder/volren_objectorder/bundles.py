"""Parameter bundles of the object-order kernels (`composite`): what travels together, by name.

Why: the kernels took up to 47 positional parameters and a float array indexed by constants; a
one-place shift compiled and rendered wrong. numba types a module-level `typing.NamedTuple` as a
named tuple (arrays allowed as members, attribute access in nopython mode, cacheable); the kernels
that take them are inlined, so a bundle costs nothing at run time.

Per frame: `Grid` (the volume), `Octree` (its min-max octree's visible cells), `View` (the
projection of the footprints, Mora et al. 2002, section 3), `Rays` (`patterns.RayTable`'s arrays),
`Tables` (the TF and its tables), `Compositing` and `PixelState`, with the lighting in
`volren.kernels.shading.ShadeParams`. Per band: `Band`,
`Occlusion` and `Scratch`. Inside the walk: `CellBlock`, `Rect`, `PixelRay` and `Sample`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class Grid(NamedTuple):
    """The volume's values (z, y, x), its cells along x, y and z, and 1 / spacing along x, y, z
    (the gradients' world units)."""

    values: np.ndarray
    ncx: int
    ncy: int
    ncz: int
    isx: float
    isy: float
    isz: float


class Octree(NamedTuple):
    """The octree of visible cells (`octree.Classification`): per level the number of visible cells
    under each node (flattened, level lv from offsets[lv]), the levels' shapes (z, y, x) and the
    leaf bits of each node one level above the cells (x + 2 y + 4 z)."""

    counts: np.ndarray
    offsets: np.ndarray
    shapes: np.ndarray
    leaves: np.ndarray


class View(NamedTuple):
    """The image and the projection of index space onto it."""

    M: np.ndarray  #: index space -> screen (`patterns.screen_matrix`)
    perspective: bool
    eye: np.ndarray  #: the eye in index space (front-to-back order of children)
    vdir: np.ndarray  #: the view direction in index space
    width: int
    height: int


class Rays(NamedTuple):
    """Each pixel's ray (`patterns.RayTable`), in index space: origin, direction (one row when
    shared), world direction, inverse direction, and its samples (`patterns.sample_t`)."""

    origin: np.ndarray
    direction: np.ndarray
    world_direction: np.ndarray
    inverse: np.ndarray
    t0: np.ndarray
    n_samples: np.ndarray  #: `RayTable.count` (a named tuple's `count` is its method)
    first: np.ndarray
    last: np.ndarray


class Tables(NamedTuple):
    """The TF exactly (breakpoints xs, RGBA rows tab), its post-classification table (`post`, one
    row: none; index (s - post_lo) * post_scale) and the pre-integration tables (index
    (s - lo) * scale; front and back: Lum et al.'s lighting tables)."""

    xs: np.ndarray
    tab: np.ndarray
    post: np.ndarray
    table: np.ndarray
    front: np.ndarray
    back: np.ndarray
    lo: float
    scale: float
    post_lo: float
    post_scale: float


class Compositing(NamedTuple):
    """How samples combine: the blend mode, pre-integration, hidden volume removal (stop at
    opacity `term`, 2 without), the largest block footprint (`block_pixels`), the step h and the
    TF's opacity unit distance du."""

    mode: int
    pre: bool
    hvr: bool
    block_pixels: int
    h: float
    du: float
    term: float


class PixelState(NamedTuple):
    """Per pixel, kept across frames: colour, the projections' accumulator, the next sample, the
    previous sample's value, index and lighting (pre-integration), and whether it is finished."""

    rgba: np.ndarray
    acc: np.ndarray
    nextk: np.ndarray
    prev_s: np.ndarray
    prev_k: np.ndarray
    prev_fd: np.ndarray
    prev_sp: np.ndarray
    finished: np.ndarray


class Band(NamedTuple):
    """Image rows r0..r1 - 1 and their counters (`composite.S_NODES`...)."""

    r0: int
    r1: int
    stats: np.ndarray


class Occlusion(NamedTuple):
    """A band's occlusion map (`occlusion.hom_layout`)."""

    hom: np.ndarray
    hl: int
    hoff: np.ndarray
    hcols: np.ndarray


class Scratch(NamedTuple):
    """A band's scratch: the walk's node stack, a block's grid points and gradients (c8, g8) and
    one cell's for `composite._fetch` (e8, eg8)."""

    stack: np.ndarray
    c8: np.ndarray
    g8: np.ndarray
    e8: np.ndarray
    eg8: np.ndarray


class CellBlock(NamedTuple):
    """Cells from (x0, y0, z0); `cells` = visible cells' bits + 256 size (1 or 2 cells a side)."""

    x0: int
    y0: int
    z0: int
    cells: int


class Rect(NamedTuple):
    """Columns c0..c1 and rows q0..q1 of the image."""

    c0: int
    c1: int
    q0: int
    q1: int


class PixelRay(NamedTuple):
    """Pixel p's ray in a block: origin (ox, oy, oz) relative to the block, direction (dx, dy, dz),
    half vector (hx, hy, hz), and its samples (`patterns.sample_t`: t0, first, last, ns)."""

    p: int
    ox: float
    oy: float
    oz: float
    dx: float
    dy: float
    dz: float
    hx: float
    hy: float
    hz: float
    t0: float
    first: float
    last: float
    ns: int


class Sample(NamedTuple):
    """A sample's value s and lighting (diffuse factor fd, specular term sp; 1, 0 unshaded)."""

    s: float
    fd: float
    sp: float


class Unprojection(NamedTuple):
    """The camera for `patterns.ray_table`: inv maps NDC to world, the image is width x height, the
    view direction (world) and the distance from the near to the far plane along it."""

    inv: np.ndarray
    width: int
    height: int
    view_dir: np.ndarray
    t_far_eye: float


class IndexBox(NamedTuple):
    """The volume's grid: world origin and spacing, its upper corner in index space, and the clip
    region's half-spaces in index space (`ClipRegion.half_spaces_in_grid`; (0, 4): none)."""

    origin: np.ndarray
    spacing: np.ndarray
    upper: np.ndarray
    planes: np.ndarray
