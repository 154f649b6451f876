"""Tables by segment length: pre-integration tables (`volren.model.preintegration`, exact and
cached there) and post-classification LUTs, gathered into one array per frame kernel.

Why by length: a parallel view has one segment length, and its table is exact. Under
perspective every intermediate ray has its own length (the same for all its slabs), so lengths
are snapped to a geometric grid L_ref r^i (r = `LENGTH_RATIO`, anchored at a fixed length so the
grid does not move with the camera): the opacity of a segment is off by at most (r - 1) / 2 of its
optical depth, 0.5% at r = 1.01, and the tables of a turning camera are mostly the ones
already made. Each length's table is computed once per TF version and kept in a pool.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from volren.model import TransferFunction1D
from volren.model.preintegration import lighting_tables, preintegrate

#: Ratio between neighbouring lengths of the perspective grid.
LENGTH_RATIO = 1.01


def snap_lengths(lengths: NDArray[np.float64], reference: float) -> tuple[NDArray[np.int32], NDArray[np.float64]]:
    """Per-pixel grid index into the returned sorted unique grid lengths."""
    ids = np.rint(np.log(lengths / reference) / math.log(LENGTH_RATIO)).astype(np.int64)
    unique, inverse = np.unique(ids, return_inverse=True)
    return inverse.reshape(lengths.shape).astype(np.int32), reference * LENGTH_RATIO ** unique.astype(np.float64)


def post_lut(tf: TransferFunction1D, n: int, lo: float, hi: float, length: float) -> NDArray[np.float32]:
    """(n, 4): colour (not premultiplied) and the opacity of half a segment of `length` at the
    table's values s_k = lo + (hi - lo) k / (n - 1): each sample stands for half of the segment on
    either side (the seed's opacity correction, 1 - (1 - a)^(d / d_u))."""
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

    def gather(self, tf: TransferFunction1D, n: int, lo: float, hi: float, lengths: NDArray[np.float64]) -> NDArray[np.int32]:
        """Pool slots of `lengths`, computing the tables not in the pool yet."""
        missing = [float(x) for x in lengths if float(x) not in self.slots]
        if missing:
            fronts, backs = [], []
            for length in missing:
                if self.kind == "post":
                    fronts.append(post_lut(tf, n, lo, hi, length))
                elif self.kind == "pre":
                    fronts.append(preintegrate(tf, n, step=length, value_range=(lo, hi)))
                else:
                    lit = lighting_tables(tf, n, step=length, value_range=(lo, hi))
                    fronts.append(lit.front)
                    backs.append(lit.back)
            base = len(self.slots)
            self.front = self._store(self.front, base, fronts)
            if backs:
                self.back = self._store(self.back, base, backs)
            for i, length in enumerate(missing):
                self.slots[length] = base + i
        return np.array([self.slots[float(x)] for x in lengths], np.int32)

    @staticmethod
    def _store(pool: NDArray[np.float32] | None, base: int, tables: list) -> NDArray[np.float32]:
        """`tables` written at slots base.., the pool grown by doubling (not copied every frame)."""
        need = base + len(tables)
        if pool is None or pool.shape[0] < need:
            grown = np.empty((max(need, 2 * (0 if pool is None else pool.shape[0]), 4),) + tables[0].shape, np.float32)
            if pool is not None:
                grown[:base] = pool[:base]
            pool = grown
        for i, table in enumerate(tables):
            pool[base + i] = table
        return pool

    @property
    def nbytes(self) -> int:
        return sum(a.nbytes for a in (self.front, self.back) if a is not None)
