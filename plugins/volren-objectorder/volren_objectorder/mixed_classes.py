"""A label or multi-channel volume's classification for the object-order walk: the shared kernels'
tables (`volren.kernels.label_sample`, `volren.kernels.channel_sample`) and the octree's visible cells.

Why the octree must know the labels and channels: the walk skips cells the classification leaves
transparent (`octree`), and with a TF per label a cell is transparent when every class at its eight
corners has zero opacity over the cell's range of values (Real-Time Volume Graphics, section 16.5:
the sample blends only its corners' classes), with a TF per channel when every drawn channel has
zero opacity over that channel's range in the cell (Max 1995: the channels' extinctions add). A cell
whose corners all hold hidden labels is then never visited, so hidden labels cost no samples; only
cells on a boundary with a drawn label are sampled (a hidden label fades its neighbour out there).
Visibility uses the exact TFs, as the plain classification does, so a label scene whose labels all
draw alike visits the plain frame's cells.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from volren.kernels.mixed_inputs import ChannelClassification, LabelClassification
from volren.model import TransferFunction1D, UniformVolume
from volren.model.channels import ChannelTransferFunction
from volren.model.labels import MIXED, LabelTransferFunction, cell_classes
from volren.model.transfer_function import MAX_OPACITY
from volren.model.volume import spanning
from volren_objectorder.octree import Classification, MinMaxOctree, _cell_ranges, _classify, _visible_on

#: The memory the label classes' tables may take together (many classes: fewer entries each).
LABEL_TABLES_BYTES = 256 * 2**20
#: Entries per table where the `classification_table` option asks for none (0: exact classification,
#: which the shared kernels do not offer).
DEFAULT_TABLE = 4096


@njit(nogil=True, cache=True, inline="always")
def _class_visible(xs, alphas, starts, c, a, b):
    """Whether class c's opacity (its control points xs[starts[c]:starts[c + 1]]) is non-zero on [a, b]."""
    return _visible_on(xs[starts[c] : starts[c + 1]], alphas[starts[c] : starts[c + 1]], a, b)


@njit(nogil=True, cache=True, parallel=True)
def _classify_labels(own_lo, own_hi, labels, lookup, cells, xs, alphas, starts, out):
    """out[cell] = 1 where a class at one of the cell's corners (`cells`: the one they share, else
    `MIXED`: each corner's label looked up) has opacity somewhere on the cell's range; 0 for a cell
    with a non-finite corner."""
    nz, ny, nx = own_lo.shape
    top = lookup.shape[0]
    for k in prange(nz):
        for j in range(ny):
            for i in range(nx):
                a = own_lo[k, j, i]
                b = own_hi[k, j, i]
                if a > b:
                    out[k, j, i] = 0
                    continue
                c = cells[k, j, i]
                if c != MIXED:
                    out[k, j, i] = 1 if c >= 0 and _class_visible(xs, alphas, starts, c, a, b) else 0
                    continue
                seen = 0
                for q in range(8):
                    label = int(labels[k + (q >> 2), j + ((q >> 1) & 1), i + (q & 1)])
                    cq = lookup[label] if label < top else -1
                    if cq >= 0 and _class_visible(xs, alphas, starts, cq, a, b):
                        seen = 1
                        break
                out[k, j, i] = seen


def _opacity_points(
    tfs: list[TransferFunction1D],
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[Any]]:
    """(xs, alphas, starts): the TFs' opacity control points end to end, TF c's at starts[c]:starts[c + 1]."""
    points = [tf.opacity_points for tf in tfs] or [np.zeros((0, 2))]
    xs = np.ascontiguousarray(np.concatenate([p[:, 0] for p in points]), dtype=np.float64)
    alphas = np.ascontiguousarray(
        np.clip(np.concatenate([p[:, 1] for p in points]), 0.0, 1.0), dtype=np.float64
    )
    starts = np.concatenate([[0], np.cumsum([len(p) for p in points])]).astype(np.int64)
    return xs, alphas, starts


def _post_table(tf: TransferFunction1D, lo: float, hi: float, n: int, h: float) -> NDArray[np.float64]:
    """(n, 4): tf's colour and opacity of a step h at n values evenly spaced over [lo, hi]."""
    rgb, a = tf.sample(np.linspace(lo, hi, n))
    alpha = -np.expm1(h / tf.opacity_unit_distance * np.log1p(-np.minimum(a, MAX_OPACITY)))
    return np.concatenate([rgb, alpha[:, None]], axis=1)


class MixedClasses:
    """One volume's label and channel classifications, kept while the labels, styles and step stay."""

    def __init__(self) -> None:
        self._cells: tuple[tuple, NDArray[np.int16]] | None = None
        self._tables: tuple[tuple, NDArray[np.float64]] | None = None
        self._channels: (
            tuple[tuple, NDArray[Any], list[tuple[NDArray[np.float32], NDArray[np.float32]]]] | None
        ) = None

    def labels(self, volume: UniformVolume, tf: LabelTransferFunction, h: float, entries: int,
               octree: MinMaxOctree) -> tuple[LabelClassification, Classification]:  # fmt: skip
        """The `LabelClassification` of a step h (tables of `entries` entries, fewer where many classes
        would take more than `LABEL_TABLES_BYTES`) and the octree's cells where some corner class has
        opacity."""
        labels = volume.labels
        assert labels is not None  # `render` refuses a label TF on a volume without labels
        classes = tf.classes(labels.max_label)
        key = (labels.digest, classes.lookup.tobytes())
        if self._cells is None or self._cells[0] != key:
            self._cells = (key, cell_classes(labels.values, classes.lookup, labels.boundary))
        cells = self._cells[1]
        vlo, vhi = volume.value_range
        tlo, thi = tf.value_range
        lo, hi = spanning(min(vlo, tlo), max(vhi, thi))
        n = max(16, min(entries or DEFAULT_TABLE, LABEL_TABLES_BYTES // (32 * max(len(classes.tfs), 1))))
        table_key = ("labels", tf.state(), h, n, lo, hi)
        if self._tables is None or self._tables[0] != table_key:
            post = np.zeros((max(len(classes.tfs), 1), n, 4))
            for c, class_tf in enumerate(classes.tfs):
                post[c] = _post_table(class_tf, lo, hi, n, h)
            self._tables = (table_key, post)
        xs, alphas, starts = _opacity_points(list(classes.tfs))

        def level0() -> NDArray[np.uint8]:
            out = np.empty(octree.cell_shape, np.uint8)
            _classify_labels(
                octree.lo, octree.hi, labels.values, classes.lookup, cells, xs, alphas, starts, out
            )
            return out

        visible = octree.classify_cells(
            ("labels", key, xs.tobytes(), alphas.tobytes(), starts.tobytes()), level0
        )
        table = LabelClassification(labels.values, classes.lookup, cells, self._tables[1], float(h), float(lo),
                                    float((n - 1) / (hi - lo)))  # fmt: skip
        return table, visible

    def channels(self, volume: UniformVolume, tf: ChannelTransferFunction, h: float, entries: int,
                 octree: MinMaxOctree) -> tuple[ChannelClassification, Classification]:  # fmt: skip
        """The `ChannelClassification` of a step h (a table of `entries` entries per drawn channel, of
        colour and depth w tau h) and the octree's cells where some drawn channel has opacity over its
        own range there."""
        channels = volume.channels
        assert channels is not None  # `render` refuses a channel TF on a volume without its channels
        drawn = [c for c in range(tf.count) if tf.drawn_weight(c) > 0.0]
        key = (channels.digest, tuple(drawn))
        if self._channels is None or self._channels[0] != key:
            picked = channels.values[drawn] if drawn else channels.values[:1]
            values = np.ascontiguousarray(picked if picked.dtype == np.uint8 else picked.astype(np.float32))
            ranges = []
            for row in range(len(drawn)):
                lo_c = np.empty(octree.cell_shape, np.float32)
                hi_c = np.empty(octree.cell_shape, np.float32)
                _cell_ranges(np.ascontiguousarray(values[row], dtype=np.float32), lo_c, hi_c)
                ranges.append((lo_c, hi_c))
            self._channels = (key, values, ranges)
        _, values, ranges = self._channels
        n = entries or DEFAULT_TABLE
        post = np.zeros((len(values), n, 4))
        lo = np.zeros(len(values))
        scale = np.ones(len(values))
        for row, c in enumerate(drawn):
            class_tf = tf.tfs[c]
            vlo, vhi = channels.value_ranges[c]
            tlo, thi = class_tf.value_range
            lo[row], hi = spanning(min(vlo, tlo), max(vhi, thi))
            scale[row] = (n - 1) / (hi - lo[row])
            rgb, a = class_tf.sample(np.linspace(lo[row], hi, n))
            post[row, :, :3] = rgb
            post[row, :, 3] = (
                tf.drawn_weight(c)
                * h
                / class_tf.opacity_unit_distance
                * -np.log1p(-np.minimum(a, MAX_OPACITY))
            )
        points = [tf.tfs[c].opacity_points.tobytes() for c in drawn]

        def level0() -> NDArray[np.uint8]:
            out = np.zeros(octree.cell_shape, np.uint8)
            one = np.empty(octree.cell_shape, np.uint8)
            for row, c in enumerate(drawn):
                xs, alphas, _ = _opacity_points([tf.tfs[c]])
                lo_c, hi_c = ranges[row]
                _classify(lo_c, hi_c, lo_c, hi_c, xs, alphas, one)
                out |= one
            return out

        visible = octree.classify_cells(("channels", key, tuple(points)), level0)
        return ChannelClassification(values, post, float(h), lo, scale), visible
