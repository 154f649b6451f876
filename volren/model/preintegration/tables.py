"""Pre-integration tables: what renderers call.

Conventions shared by every table here:
- entry [i, j] belongs to a segment along which the data value runs linearly from s_i at the
  FRONT (nearer the eye) to s_j at the BACK, s_k = lo + (hi - lo) k / (n - 1), (lo, hi) the TF's
  `value_range` unless given;
- it is DESIGN.md's emission-absorption model integrated over the segment's length (world
  units), as float32 premultiplied RGBA: 0 <= colour <= alpha <= 1;
- 3D tables (for segments of varying length, e.g. tetrahedra) are indexed [length, i, j, :].

How (see `tf_bins` and `subrange`): the value axis is split into n_t - 1 = oversampling (n - 1)
bins that carry the TF's exact mean extinction and emission; an entry composites the bins its
value span covers, each as a homogeneous slab of the entry's length divided among them. The
optical depth (hence the opacity) is exact for any n; the colour treats each bin as homogeneous,
an error that falls as n_t^-2 and grows with the optical depth of one bin (measured by
`python -m benchmarks.preint` and tests/model/preintegration/test_accuracy.py). It depends on n_t, not
on n, so `oversampling` (by default enough for n_t >= AUTO_MIN_ENTRIES) makes a small table exact at
its entries to the same degree as a large one. The diagonal is the homogeneous segment's closed
form: alpha = 1 - exp(-tau(s) L), colour = c(s) alpha.

Lighting tables (Lum, Wilson and Ma 2004, interpolated pre-integrated lighting): the emission
along a segment is split into a part weighted by (1 - w) and a part weighted by w, w running from
0 at the front to 1 at the back, so a renderer can interpolate lighting linearly between the
front and back samples:

    rgb = ka (Df + Db) + kd (Df l_f + Db l_b) + ks (Sf h_f + Sb h_b),  alpha = opacity

with l = |N . L| and h = max(N . H, 0)^p at the front and back samples, D the diffuse (TF colour)
and S the specular (white) tables. `LightingTables` packs them as Lum et al. do into two RGBA
tables: front = (Df, opacity) and back = (Db, Sb); Sf = opacity - Sb and Df + Db = the plain
table's colour, to float32 rounding. Where a sample has no gradient (DESIGN.md: no shading) a
renderer uses l = 1, h = 0 with ka = 1, kd = 0 for that side.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from volren.errors import VolrenError
from volren.model.preintegration.approximate import integral_function_table
from volren.model.preintegration.brute_force import brute_force_tables
from volren.model.preintegration.cache import TableCache
from volren.model.preintegration.segment_math import emission_centres
from volren.model.preintegration.subrange import subrange_tables
from volren.model.preintegration.tf_bins import point_values, tf_bins
from volren.model.transfer_function import TransferFunction1D

#: Refuse tables (all outputs of one call together) above this many bytes.
MAX_TABLE_BYTES = 4 << 30
#: Most bins (n_t - 1) the value axis may be split into.
MAX_BINS = 1 << 16
#: With oversampling=None, small tables are computed on at least this many TF entries n_t: the
#: error falls as n_t^-2 whatever n is, and below ~1000 entries thick segments lose 1e-3 and more.
AUTO_MIN_ENTRIES = 1024

#: The cache `preintegrate` and `lighting_tables` use unless given another (or None).
TABLE_CACHE = TableCache()


@dataclass(frozen=True)
class TableSpec:
    """What a table depends on besides the TF; with the TF's version it is the cache key."""

    n: int
    lo: float
    hi: float
    lengths: tuple[float, ...]
    oversampling: int

    @property
    def bins(self) -> int:
        return self.oversampling * (self.n - 1)

    def values(self) -> NDArray[np.float64]:
        """s_k, k = 0 .. n - 1."""
        values = self.lo + (self.hi - self.lo) * (np.arange(self.n, dtype=np.float64) / (self.n - 1))
        values[-1] = self.hi
        return values


@dataclass(frozen=True)
class LightingTables:
    """Front- and back-weighted tables for interpolated pre-integrated lighting (module docstring).

    front [..., :3] diffuse front-weighted, [..., 3] the segment's opacity;
    back  [..., :3] diffuse back-weighted,  [..., 3] specular (white) back-weighted.
    """

    front: NDArray[np.float32]
    back: NDArray[np.float32]

    @property
    def arrays(self) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
        return (self.front, self.back)

    @property
    def opacity(self) -> NDArray[np.float32]:
        return self.front[..., 3]

    @property
    def diffuse_front(self) -> NDArray[np.float32]:
        return self.front[..., :3]

    @property
    def diffuse_back(self) -> NDArray[np.float32]:
        return self.back[..., :3]

    @property
    def specular_back(self) -> NDArray[np.float32]:
        return self.back[..., 3]

    @property
    def specular_front(self) -> NDArray[np.float32]:
        return self.front[..., 3] - self.back[..., 3]


# ------------------------------------------------------------------------------- validation
def _check_tf(tf: object) -> TransferFunction1D:
    if not isinstance(tf, TransferFunction1D):
        raise VolrenError(f"pre-integration needs a 1D transfer function, got {type(tf).__name__}")
    return tf


def _check_lengths(step: float | None, lengths: ArrayLike | None) -> tuple[tuple[float, ...], bool]:
    """(lengths, is_3d) from exactly one of `step` (a 2D table) and `lengths` (a 3D table)."""
    if (step is None) == (lengths is None):
        raise VolrenError("give exactly one of step= (a 2D table) and lengths= (a 3D table)")
    if step is not None:
        if isinstance(step, (bool, np.bool_)) or not isinstance(step, (int, float, np.integer, np.floating)):
            raise VolrenError(f"step must be one number, got {step!r}")
        if not (math.isfinite(step) and step > 0):
            raise VolrenError(f"step must be positive and finite, got {step!r}")
        return (float(step),), False
    try:
        values = np.asarray(lengths, dtype=np.float64)
    except (TypeError, ValueError):
        raise VolrenError(f"lengths must be numbers, got {lengths!r}") from None
    if values.ndim != 1 or values.size == 0:
        raise VolrenError(f"lengths must be a non-empty 1D list of numbers, got shape {values.shape}")
    if not np.all(np.isfinite(values)) or np.any(values < 0):
        raise VolrenError("lengths must be finite and >= 0")
    return tuple(float(v) for v in values), True


def _spec(
    tf: TransferFunction1D,
    n: int,
    step: float | None,
    lengths: ArrayLike | None,
    value_range: Sequence[float] | None,
    oversampling: int | None,
    outputs: int,
) -> tuple[TableSpec, bool]:
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 2:
        raise VolrenError(f"a pre-integration table needs an integer size n >= 2, got {n!r}")
    if oversampling is None:
        oversampling = -(-(AUTO_MIN_ENTRIES - 1) // (n - 1))
    if isinstance(oversampling, bool) or not isinstance(oversampling, (int, np.integer)) or oversampling < 1:
        raise VolrenError(f"oversampling must be an integer >= 1, got {oversampling!r}")
    if oversampling * (n - 1) > MAX_BINS:
        raise VolrenError(
            f"n_t - 1 = oversampling (n - 1) = {oversampling * (n - 1)} exceeds {MAX_BINS} bins"
        )
    try:
        lo, hi = (float(v) for v in (tf.value_range if value_range is None else value_range))
    except (TypeError, ValueError):
        raise VolrenError(f"value range must be two numbers (lo, hi), got {value_range!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and math.isfinite(hi - lo)) or hi < lo:
        raise VolrenError(f"value range must be finite with lo <= hi, got ({lo}, {hi})")
    all_lengths, is_3d = _check_lengths(step, lengths)
    size = outputs * len(all_lengths) * int(n) * int(n) * 4 * 4
    if size > MAX_TABLE_BYTES:
        raise VolrenError(
            f"a {len(all_lengths)} x {n} x {n} pre-integration table would take {size / 2**30:.1f} GiB "
            f"(limit {MAX_TABLE_BYTES / 2**30:.0f} GiB)"
        )
    return TableSpec(int(n), lo, hi, all_lengths, int(oversampling)), is_3d


# ----------------------------------------------------------------------------- computation
def _exact_tables(
    tf: TransferFunction1D, spec: TableSpec, weighted: bool, brute_force: bool = False
) -> tuple[NDArray[np.float32], NDArray[np.float32] | None]:
    """(table (L, n, n, 4), back-weighted table or None) in float32."""
    n = spec.n
    lengths = np.asarray(spec.lengths, dtype=np.float64)
    bins = tf_bins(tf, spec.lo, spec.hi, spec.bins)
    out = np.empty((len(lengths), n, n, 4), dtype=np.float32)
    back = np.empty_like(out) if weighted else np.empty((1, 1, 1, 4), dtype=np.float32)
    kernel = brute_force_tables if brute_force else subrange_tables
    kernel(bins.tau, bins.color, spec.oversampling, n, lengths, weighted, out, back)
    diag_tau, diag_color = point_values(tf, spec.values())
    depth = lengths[:, None] * diag_tau[None, :]  # (L, n)
    alpha = -np.expm1(-depth)
    k = np.arange(n)
    out[:, k, k, 3] = alpha
    out[:, k, k, :3] = diag_color[None] * alpha[..., None]
    if not weighted:
        return out, None
    centre = emission_centres(np.ascontiguousarray(depth))
    back[:, k, k, 3] = centre * alpha
    back[:, k, k, :3] = diag_color[None] * (centre * alpha)[..., None]
    back[:, k, k] = np.minimum(back[:, k, k], out[:, k, k])  # float32 rounding of centre * alpha
    return out, back


def _lighting_from(out: NDArray[np.float32], back: NDArray[np.float32]) -> LightingTables:
    front = np.empty_like(out)
    front[..., :3] = out[..., :3] - back[..., :3]
    front[..., 3] = out[..., 3]
    return LightingTables(front, back)


def _squeeze(table: NDArray, is_3d: bool) -> NDArray:
    return table if is_3d else table[0]


def _key(kind: str, tf: TransferFunction1D, spec: TableSpec, is_3d: bool) -> tuple:
    """A 2D table and a 3D table of one length share a spec but not a shape."""
    return (kind, tf.version, spec, is_3d)


# ---------------------------------------------------------------------------------- public
def preintegrate(
    tf: TransferFunction1D,
    n: int = 256,
    step: float | None = None,
    *,
    lengths: ArrayLike | None = None,
    value_range: Sequence[float] | None = None,
    oversampling: int | None = None,
    cache: TableCache | None = TABLE_CACHE,
) -> NDArray[np.float32]:
    """The exact pre-integration table in O(n^2) per length: (n, n, 4) for a segment length
    `step`, or (len(lengths), n, n, 4) for `lengths` (world units). Read-only when cached."""
    tf = _check_tf(tf)
    spec, is_3d = _spec(tf, n, step, lengths, value_range, oversampling, outputs=1)

    def compute() -> NDArray[np.float32]:
        return _squeeze(_exact_tables(tf, spec, weighted=False)[0], is_3d)

    return compute() if cache is None else cache.get_or_compute(_key("exact", tf, spec, is_3d), compute)


def lighting_tables(
    tf: TransferFunction1D,
    n: int = 256,
    step: float | None = None,
    *,
    lengths: ArrayLike | None = None,
    value_range: Sequence[float] | None = None,
    oversampling: int | None = None,
    cache: TableCache | None = TABLE_CACHE,
) -> LightingTables:
    """Front- and back-weighted tables for interpolated pre-integrated lighting, O(n^2) per length."""
    tf = _check_tf(tf)
    spec, is_3d = _spec(tf, n, step, lengths, value_range, oversampling, outputs=2)

    def compute() -> LightingTables:
        out, back = _exact_tables(tf, spec, weighted=True)
        tables = _lighting_from(out, back)  # type: ignore[arg-type]
        return LightingTables(_squeeze(tables.front, is_3d), _squeeze(tables.back, is_3d))

    return compute() if cache is None else cache.get_or_compute(_key("lighting", tf, spec, is_3d), compute)


def preintegrate_brute_force(
    tf: TransferFunction1D,
    n: int,
    step: float | None = None,
    *,
    lengths: ArrayLike | None = None,
    value_range: Sequence[float] | None = None,
    oversampling: int | None = None,
    lighting: bool = False,
) -> NDArray[np.float32] | LightingTables:
    """The same table (or lighting tables) as `preintegrate` by compositing every entry's bins
    one by one in float64, O(n^2 n_t): for tests and the benchmark. Never cached."""
    tf = _check_tf(tf)
    spec, is_3d = _spec(tf, n, step, lengths, value_range, oversampling, outputs=2 if lighting else 1)
    out, back = _exact_tables(tf, spec, weighted=lighting, brute_force=True)
    if not lighting:
        return _squeeze(out, is_3d)
    tables = _lighting_from(out, back)  # type: ignore[arg-type]
    return LightingTables(_squeeze(tables.front, is_3d), _squeeze(tables.back, is_3d))


def preintegrate_approximate(
    tf: TransferFunction1D,
    n: int,
    step: float,
    *,
    value_range: Sequence[float] | None = None,
    oversampling: int | None = None,
) -> NDArray[np.float32]:
    """Engel et al.'s integral-function table (no attenuation inside a segment), for comparison."""
    tf = _check_tf(tf)
    spec, _ = _spec(tf, n, step, None, value_range, oversampling, outputs=1)
    bins = tf_bins(tf, spec.lo, spec.hi, spec.bins)
    diag_tau, diag_color = point_values(tf, spec.values())
    out = np.empty((spec.n, spec.n, 4), dtype=np.float32)
    integral_function_table(
        bins.tau, bins.color, spec.oversampling, spec.n, spec.lengths[0], diag_tau, diag_color, out
    )
    return out
