"""Parameter bundles of the compositing kernels (`composite`): what travels together, by name.

Why: the kernels took up to 53 positional parameters; two of the same type swapped by one place
compile and render wrong. numba types a module-level `typing.NamedTuple` as a named tuple (arrays
allowed as members, attribute access in nopython mode, cacheable), so a bundle costs nothing at run
time once the kernels are inlined.

Per frame: `SlabGeometry` (the sheared slices and how the intermediate rays cross them, Lacroute &
Levoy 1994, section 3), `Intermediate` (the intermediate image and its per-pixel buffers),
`Classification` (the tables a segment is looked up in), `Runs` (the run-length encoded blocks that
may be visible), `Termination`, `ViewVectors` (with `volren.kernels.shading.ShadeParams`), `Clipping`
and `Jitter`. Per slab, scanline, ray and
segment end, inside the kernels: `SlabMap`, `Scanline`, `SlabSegment`, `Ray` and `SegmentEnd`.

A parallel loop (`prange`) must not touch a bundle whose arrays it writes, nor write through one in a
kernel it inlines: numba passes a bundle's members as more arguments that it declares unaliased with
the others, and drops stores through a bundle's member there as dead code. The kernels take such
arrays out before the loop and pass them one by one (or in a bundle built inside the loop, to a
kernel called, not inlined).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class SlabGeometry(NamedTuple):
    """The volume's slices along the principal axis and the factorization's maps: slice k's sample
    under intermediate pixel (q, p) lies at a = alpha_a[k] + beta_a[k] p, b = alpha_b[k] + beta_b[k] q."""

    values: np.ndarray  #: (slices, b, a) copy of the volume along the principal axis
    has_nan: bool  #: whether any value is NaN (the fast spans test for them only then)
    order: np.ndarray  #: slice indices front to back; slab m lies between order[m - 1] and order[m]
    slab_frac: np.ndarray  #: slab m's length in whole slabs (below 1 for a short last slab)
    planes: int  #: sub-planes per slab (the render setting `step`)
    alpha_a: np.ndarray
    beta_a: np.ndarray
    alpha_b: np.ndarray
    beta_b: np.ndarray
    rows: np.ndarray  #: the intermediate scanlines to draw
    row_block: int  #: consecutive scanlines a thread takes at a time
    inv_spacing: np.ndarray  #: 1 / spacing along a, b, c (gradients in world units)


class Intermediate(NamedTuple):
    """The intermediate image and its per-pixel buffers (reused from frame to frame)."""

    rgba: np.ndarray  #: (h, w, 4) premultiplied RGBA float32
    buf_x: (
        np.ndarray
    )  #: table coordinate at the back of the pixel's last segment (Schulze et al.'s buffer slice)
    buf_d: np.ndarray  #: ... its diffuse factor, when shading
    buf_s: np.ndarray  #: ... its specular term, when shading
    buf_len: np.ndarray  #: length so far of a jittered segment open across slabs, in whole segments
    stamp: np.ndarray  #: the sub-plane the buffered values belong to (-1: none)
    skip: np.ndarray  #: skip links past opaque pixels (early ray termination)
    counters: np.ndarray  #: per row: segments composited, pixels skipped as empty, pixels terminated


class Classification(NamedTuple):
    """The tables a segment is looked up in, by table coordinate x = (s - lo) * scale."""

    layers: np.ndarray  #: table layer (segment length) per pixel, or [0, 0] for all
    per_pixel_layer: bool
    table: np.ndarray  #: pre-integrated (layer, x front, x back, RGBA), front-weighted when shading
    table_back: np.ndarray  #: the back-weighted table of Lum et al.'s interpolated lighting
    lut: np.ndarray  #: post-classified (layer, x, RGBA), colour not premultiplied
    preintegrated: bool
    bilinear_lookup: bool  #: bilinear (else nearest) lookups
    lo: float
    scale: float


class Runs(NamedTuple):
    """Run-length runs of the blocks of cells that may be visible (`classified`)."""

    on: bool
    offsets: np.ndarray  #: first run of (slab, block row), flattened
    starts: np.ndarray
    ends: np.ndarray
    extent: int  #: cells a block reaches past its anchor
    slab: np.ndarray  #: the runs' slab number of compositing slab m


class Termination(NamedTuple):
    """Early ray termination: a pixel at or above `alpha` takes no more segments."""

    on: bool
    alpha: float


class ViewVectors(NamedTuple):
    """What Blinn-Phong shading needs besides `ShadeParams` (which the kernels take by itself: numba's
    parallel loops take apart a bundle that is an argument, one level deep): the half vector of a
    parallel projection, or the rays' directions under perspective (a half vector per pixel)."""

    half: np.ndarray  #: H of every ray (parallel projection)
    ray_dirs: np.ndarray  #: (h, w, 3) unit ray directions under perspective, else (1, 1, 3)


class Clipping(NamedTuple):
    """The near and far planes: pixel (q, p)'s ray is drawn for u in [lo[q, p], hi[q, p]] only."""

    on: bool
    lo: np.ndarray
    hi: np.ndarray


class Jitter(NamedTuple):
    """Jittered sample planes: pixel (q, p)'s samples at offsets[q, p] of the way between planes."""

    on: bool
    offsets: np.ndarray


class SlabMap(NamedTuple):
    """Slab between slices kf (front) and kb (back): pixel p's ray crosses them at
    a = af0 + afs p and a = ab0 + abs_ p."""

    kf: int
    kb: int
    af0: float
    afs: float
    ab0: float
    abs_: float


class Scanline(NamedTuple):
    """Row q of the intermediate image in sub-plane `plane`, and the cell rows its rays meet on the
    front (ibf, weight fbf) and back slice."""

    q: int
    plane: int
    ibf: int
    fbf: float
    ibb: int
    fbb: float


class SlabSegment(NamedTuple):
    """One ray's segment through a slab: from (af, bf) on slice kf to (ab, bb) on slice kb."""

    kf: int
    kb: int
    af: float
    ab: float
    bf: float
    bb: float


class Ray(NamedTuple):
    """Intermediate pixel (q, p): its table layer and its headlight half vector."""

    q: int
    p: int
    layer: int
    hx: float
    hy: float
    hz: float


class SegmentEnd(NamedTuple):
    """A segment's end: table coordinate, and (1, 0) or its Blinn-Phong diffuse factor and specular term."""

    x: float
    diffuse: float
    specular: float
