"""Tables by segment length: pre-integration tables (`volren.model.preintegration`, exact and
cached there) and post-classification LUTs, gathered into one array per frame kernel.

Why by length: a parallel view has one segment length, and its table is exact. Under
perspective every intermediate ray has its own length (the same for all its slabs), so lengths
are snapped to a geometric grid L_ref r^i (r: the renderer's option `length_ratio`, by default
`LENGTH_RATIO`; L_ref fixed, so the grid does not move with the camera): the opacity of a segment is
off by at most (r - 1) / 2 of its optical depth, 1% at r = 1.02, and the tables of a turning
camera are mostly the ones already made; a coarser grid makes fewer tables per TF (a TF drag's
previews make new ones every frame). Each length's table is computed once per TF version and kept in a pool; a
frame that needs lengths the pool lacks computes them in one batch with the lengths that any view
along the same axis needs (the renderer's choice) and `GRID_MARGIN` more on each side, so that a
turning camera does not wait for tables (about 2.7 ms each at n = 256, batched).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit
from numpy.typing import NDArray

from volren.model import TransferFunction1D
from volren.model.preintegration import lighting_tables, preintegrate

#: Ratio between neighbouring lengths of the perspective grid (the option `length_ratio`'s default).
LENGTH_RATIO = 1.02
#: Extra grid lengths computed on each side when a frame needs new ones.
GRID_MARGIN = 3


def grid_ids(shortest: float, longest: float, reference: float, ratio: float) -> tuple[int, int]:
    """The first and last grid index that lengths in [shortest, longest] snap to."""
    step = math.log(ratio)
    return round(math.log(shortest / reference) / step), round(math.log(longest / reference) / step)


def grid_length(i: int, reference: float, ratio: float) -> float:
    return reference * ratio**i


@njit(nogil=True, cache=True)
def pixel_slots(col_d2, row_d2, dc2, bounds, slot_of_id, out):
    """out[q, p] = pool slot of the grid length nearest (in ratio) to the pixel's segment length,
    found by walking `bounds` (the squares, in the units of col_d2 + row_d2 + dc2, of the lengths
    halfway in ratio between neighbouring grid lengths): lengths vary slowly along a row, so
    this is a comparison or two per pixel instead of a logarithm."""
    last = slot_of_id.shape[0] - 1
    for q in range(
        out.shape[0]
    ):  # serial: about a millisecond, less than a parallel barrier costs under load
        i = 0
        for p in range(out.shape[1]):
            s = col_d2[p] + row_d2[q] + dc2
            while i > 0 and s < bounds[i - 1]:
                i -= 1
            while i < last and s >= bounds[i]:
                i += 1
            out[q, p] = slot_of_id[i]


def slot_bounds(
    id_lo: int, id_hi: int, reference: float, inv_norm: float, ratio: float
) -> NDArray[np.float64]:
    """The `bounds` of `pixel_slots` for grid indices id_lo..id_hi."""
    halfway = reference * ratio ** (np.arange(id_lo, id_hi, dtype=np.float64) + 0.5)
    return (halfway / inv_norm) ** 2


def post_lut(tf: TransferFunction1D, n: int, lo: float, hi: float, length: float) -> NDArray[np.float32]:
    """(n, 4): colour (not premultiplied) and the opacity of half a segment of `length` at the
    table's values s_k = lo + (hi - lo) k / (n - 1): each sample stands for half of the segment on
    either side (Schulze et al.'s opacity correction, 1 - (1 - a)^(d / d_u))."""
    values = lo + (hi - lo) * np.arange(n) / (n - 1)
    rgb, a = tf.sample(values)
    a = np.minimum(a, 1.0 - 1e-6)
    out = np.empty((n, 4), np.float32)
    out[:, :3] = rgb
    out[:, 3] = -np.expm1(0.5 * length / tf.opacity_unit_distance * np.log1p(-a))
    return out


@dataclass
class TablePool:
    """Tables for one TF version, table size and value range, by segment length."""

    key: tuple
    kind: str  #: "pre", "lit" (lighting front/back) or "post"
    slots: dict[float, int] = field(default_factory=dict)
    front: NDArray[np.float32] | None = None
    back: NDArray[np.float32] | None = None

    def gather(self, tf: TransferFunction1D, n: int, lo: float, hi: float, lengths: list[float],
               extra: list[float] | None = None) -> NDArray[np.int32]:  # fmt: skip
        """Pool slots of `lengths`; when some are missing, they and `extra` are computed in one batch."""
        if any(x not in self.slots for x in lengths):
            missing = [x for x in dict.fromkeys(lengths + (extra or [])) if x not in self.slots]
            backs: NDArray[np.float32] | None = None
            if self.kind == "post":
                fronts = np.stack([post_lut(tf, n, lo, hi, length) for length in missing])
            elif self.kind == "pre":
                fronts = preintegrate(tf, n, lengths=missing, value_range=(lo, hi), cache=None)
            else:
                lit = lighting_tables(tf, n, lengths=missing, value_range=(lo, hi), cache=None)
                fronts, backs = lit.front, lit.back
            base = len(self.slots)
            self.front = self._store(self.front, base, fronts)
            if backs is not None:
                self.back = self._store(self.back, base, backs)
            for i, length in enumerate(missing):
                self.slots[length] = base + i
        return np.array([self.slots[x] for x in lengths], np.int32)

    @staticmethod
    def _store(
        pool: NDArray[np.float32] | None, base: int, tables: NDArray[np.float32]
    ) -> NDArray[np.float32]:
        """`tables` written at slots base.., the pool grown by doubling (not copied every frame)."""
        need = base + len(tables)
        if pool is None or pool.shape[0] < need:
            grown = np.empty(
                (max(need, 2 * (0 if pool is None else pool.shape[0]), 4),) + tables[0].shape, np.float32
            )
            if pool is not None:
                grown[:base] = pool[:base]
            pool = grown
        pool[base:need] = tables
        return pool

    @property
    def nbytes(self) -> int:
        return sum(a.nbytes for a in (self.front, self.back) if a is not None)
