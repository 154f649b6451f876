"""What a label or multi-channel frame needs besides the plain frame's geometry: the classification
laid out like an axis copy, its tables, and runs of possibly visible blocks (`mixed_composite`).

Why on the axis copies: shear-warp samples slice by slice in (a, b, c) index order
(`factorization.PERMS`), so the labels, their cell classes (`volren.model.labels.cell_classes`) and
the channels are transposed the way `classified.ClassifiedVolume.copy` transposes the values, once
per principal axis, and a sample reads them at the point it reads the values.

Empty-space skipping (Lacroute and Levoy 1994's runs, `classified`): a block may show only where
some class's (or channel's) TF has opacity in the block's value range, so the runs are made for the
union of the visible classes' opacity supports (channels: a block is kept where any drawn channel's
range meets its own TF's support, the masks OR-ed). A hidden label costs nothing where its cells
are hidden at all eight corners: the runs are made from a copy of the values with NaN at every point
whose cells are all hidden (`classified` leaves NaN vertices out of a block's range), so a region of
hidden labels is skipped like empty space whatever its values; a point that is a corner of some
cell with a visible class keeps its value, so no visible label is ever skipped.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from volren.kernels.mixed_inputs import ChannelClassification, LabelClassification
from volren.model import TransferFunction1D, UniformVolume
from volren.model.channels import ChannelTransferFunction
from volren.model.labels import LabelClasses, LabelTransferFunction, boundary_cells, cell_classes
from volren.model.transfer_function import MAX_OPACITY
from volren.model.volume import spanning
from volren_shearwarp.classified import (
    MIN_GAP,
    OpacitySupport,
    Runs,
    _mask_from_ranges,
    _runs_from_mask,
    block_ranges,
    copy_dtype,
    range_counts,
)
from volren_shearwarp.factorization import PERMS

#: Block ranges kept per scene (by axis, extent, slab pairs and source): a turning camera reuses them.
MAX_RANGES = 12


def axis_copy(values: NDArray[Any], axis: int, dtype: Any = None) -> NDArray[Any]:
    """`values` ([z, y, x]) laid out as `classified.ClassifiedVolume.copy` lays out the values for
    principal axis `axis`: [c, b, a], contiguous."""
    a, b, c = PERMS[axis]
    return np.ascontiguousarray(np.transpose(values, (2 - c, 2 - b, 2 - a)), dtype=dtype)


def union_support(supports: list[OpacitySupport], pad: float = 0.0) -> OpacitySupport:
    """The bins where any of `supports` (over the same range and bins) has opacity, widened by `pad`
    (value units) on each side. Why the pad: `label_sample` and `channel_sample` interpolate their
    tables linearly, so a value less than one entry below the TF's support already draws something."""
    first = supports[0]
    nonzero = np.zeros(len(first.counts) - 1, bool)
    for s in supports:
        nonzero |= np.diff(s.counts) > 0
    reach = int(np.ceil(pad / (first.hi - first.lo) * len(nonzero))) + 1 if pad > 0 else 0
    if reach and nonzero.any():
        near = np.flatnonzero(nonzero)
        marks = np.zeros(len(nonzero) + 1, np.int32)
        np.add.at(marks, np.maximum(near - reach, 0), 1)
        np.add.at(marks, np.minimum(near + reach + 1, len(nonzero)), -1)
        nonzero = np.cumsum(marks[:-1]) > 0
    counts = np.zeros(len(nonzero) + 1, np.int32)
    np.cumsum(nonzero, out=counts[1:])
    digest = hashlib.sha256(
        np.packbits(nonzero).tobytes() + np.array([first.lo, first.hi]).tobytes()
    ).hexdigest()
    return OpacitySupport(first.lo, first.hi, counts, digest)


def hidden_points(cells: NDArray[np.int16]) -> NDArray[np.bool_]:
    """Grid points every cell of which is hidden at all eight corners (`cell_classes` -1): their
    value cannot show, whatever it is."""
    nz, ny, nx = cells.shape
    padded = np.ones((nz + 1, ny + 1, nx + 1), bool)  # no cell beyond the grid: it hides nothing
    padded[1:nz, 1:ny, 1:nx] = cells[:-1, :-1, :-1] == -1
    out = np.ones(cells.shape, bool)
    for dz in (0, 1):
        for dy in (0, 1):
            for dx in (0, 1):
                out &= padded[dz : dz + nz, dy : dy + ny, dx : dx + nx]
    return out


def union_runs(parts: list[tuple[tuple[NDArray, NDArray], OpacitySupport]], extent: int) -> Runs:
    """Runs of the blocks where any part's block ranges meet its support (`classified.build_runs`,
    the masks OR-ed)."""
    bmin = parts[0][0][0]
    mask = np.zeros(bmin.shape, np.uint8)
    one = np.empty(bmin.shape, np.uint8)
    for (lo, hi), support in parts:
        _mask_from_ranges(lo, hi, range_counts(support), one)
        mask |= one
    offsets, starts, ends = _runs_from_mask(mask, MIN_GAP)
    digest = hashlib.sha256(b"".join(s.digest.encode() for _, s in parts)).hexdigest()
    return Runs(offsets, starts, ends, digest, extent, 0.0, int(mask.sum(dtype=np.int64)), int(mask.size))


def class_tables(tfs: list[TransferFunction1D], n: int, lo: NDArray, hi: NDArray, h: float,
                 weights: list[float] | None = None) -> NDArray[np.float64]:  # fmt: skip
    """(len(tfs), n, 4): each TF's colour at n values from lo[i] to hi[i], and its opacity over a
    segment h long (labels, `label_sample`), or with `weights` its depth w tau h (channels, `channel_sample`)."""
    post = np.zeros((max(len(tfs), 1), n, 4))
    for i, tf in enumerate(tfs):
        rgb, a = tf.sample(np.linspace(lo[i], hi[i], n))
        depth = -h / tf.opacity_unit_distance * np.log1p(-np.minimum(a, MAX_OPACITY))
        post[i, :, :3] = rgb
        post[i, :, 3] = -np.expm1(-depth) if weights is None else weights[i] * depth
    return post


@dataclass
class MixedScenes:
    """A volume's label and channel layouts per principal axis, made on first use, and block ranges."""

    volume: UniformVolume
    labels: dict[int, tuple[NDArray[Any], NDArray[np.int64]]] = field(default_factory=dict)
    cells: dict[tuple, NDArray[np.int16]] = field(default_factory=dict)
    masked: dict[tuple, NDArray[np.float32] | None] = field(default_factory=dict)
    channels: dict[tuple, NDArray[Any]] = field(default_factory=dict)
    ranges: dict[tuple, tuple[NDArray, NDArray]] = field(default_factory=dict)

    def _ranges(self, key: tuple, values: NDArray, support: OpacitySupport, extent: int,
                pairs: NDArray[np.int64]) -> tuple[NDArray, NDArray]:  # fmt: skip
        full = key + (extent, pairs.tobytes(), support.lo, support.hi)
        if full not in self.ranges:
            if len(self.ranges) >= MAX_RANGES:
                self.ranges.clear()
            self.ranges[full] = block_ranges(values, support, extent, pairs)
        return self.ranges[full]

    # ------------------------------------------------------------------------------ labels
    def label_layout(self, axis: int, classes: LabelClasses) -> tuple[NDArray[Any], NDArray[np.int16]]:
        """(labels, cell classes) on axis `axis`'s copy grid."""
        labels = self.volume.labels
        assert labels is not None
        if axis not in self.labels:
            self.labels.clear()  # one axis at a time: a view keeps its axis for many frames
            self.cells.clear()
            self.masked.clear()
            permuted = axis_copy(labels.values, axis)
            self.labels[axis] = (permuted, boundary_cells(permuted))
        permuted, boundary = self.labels[axis]
        key = (axis, classes.lookup.tobytes())
        if key not in self.cells:
            self.cells.clear()
            self.cells[key] = cell_classes(permuted, classes.lookup, boundary)
        return permuted, self.cells[key]

    def label_runs(self, axis: int, values: NDArray, classes: LabelClasses, cells: NDArray[np.int16],
                   vrange: tuple[float, float], extent: int, pairs: NDArray[np.int64], use_runs: bool,
                   pad: float) -> tuple[Runs | None, bool]:  # fmt: skip
        """(runs for the union of the visible classes' supports widened by `pad` (a table entry), hidden
        labels masked out, or None with `use_runs` off; whether any class can show)."""
        supports = [OpacitySupport.of(tf, *vrange) for tf in classes.tfs]
        if not supports:
            return None, False
        support = union_support(supports, pad)
        if support.empty or not use_runs:
            return None, not support.empty
        key: tuple = ("masked", axis, classes.lookup.tobytes())
        if key not in self.masked:  # None where no point is hidden
            self.masked.clear()
            hidden = hidden_points(cells)
            self.masked[key] = (
                np.where(hidden, np.float32(np.nan), values.astype(np.float32)) if hidden.any() else None
            )
        source = self.masked[key]
        if source is None:
            key, source = ("values", axis), values
        return union_runs([(self._ranges(key, source, support, extent, pairs), support)], extent), True

    def label_classification(self, axis: int, tf: LabelTransferFunction, classes: LabelClasses, n: int, h: float,
                             vrange: tuple[float, float]) -> LabelClassification:  # fmt: skip
        """The `LabelClassification` on axis `axis`'s copy grid, tables for segments h long."""
        permuted, cells = self.label_layout(axis, classes)
        tlo, thi = tf.value_range
        lo, hi = spanning(min(vrange[0], tlo), max(vrange[1], thi))
        count = len(classes.tfs)
        post = class_tables(list(classes.tfs), n, np.full(count, lo), np.full(count, hi), h)
        return LabelClassification(
            permuted, classes.lookup, cells, post, float(h), float(lo), float((n - 1) / (hi - lo))
        )

    # ---------------------------------------------------------------------------- channels
    def channel_values(self, axis: int, drawn: list[int]) -> NDArray[Any]:
        """The drawn channels on axis `axis`'s copy grid: (channels, c, b, a) in `copy_dtype`."""
        channels = self.volume.channels
        assert channels is not None
        key = (axis, tuple(drawn))
        if key not in self.channels:
            self.channels.clear()
            dtype = copy_dtype(channels.values.dtype)
            self.channels[key] = np.ascontiguousarray(
                np.stack([axis_copy(channels.values[c], axis, dtype) for c in drawn])
            )
        return self.channels[key]

    def channel_frame(self, axis: int, tf: ChannelTransferFunction, drawn: list[int], n: int, h: float,
                      extent: int, pairs: NDArray[np.int64],
                      use_runs: bool) -> tuple[ChannelClassification, Runs | None, bool]:  # fmt: skip
        """(the `ChannelClassification` on axis `axis`'s copy grid with tables for segments h long,
        the runs where any drawn channel may show (None with `use_runs` off), whether any can)."""
        channels = self.volume.channels
        assert channels is not None
        values = self.channel_values(axis, drawn)
        lo = np.zeros(len(drawn))
        hi = np.ones(len(drawn))
        parts = []
        visible = False
        for row, c in enumerate(drawn):
            vlo, vhi = channels.value_ranges[c]
            tlo, thi = tf.tfs[c].value_range
            lo[row], hi[row] = spanning(min(vlo, tlo), max(vhi, thi))
            support = union_support([OpacitySupport.of(tf.tfs[c], vlo, vhi)], (hi[row] - lo[row]) / (n - 1))
            visible |= not support.empty
            if use_runs and not support.empty:
                parts.append(
                    (self._ranges(("channel", axis, c), values[row], support, extent, pairs), support)
                )
        post = class_tables([tf.tfs[c] for c in drawn], n, lo, hi, h, [tf.drawn_weight(c) for c in drawn])
        classes = ChannelClassification(values, post, float(h), lo, (n - 1) / (hi - lo))
        return classes, union_runs(parts, extent) if parts else None, visible
