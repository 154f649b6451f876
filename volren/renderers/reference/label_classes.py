"""The label classes of a `LabelTransferFunction` as the reference's kernels read them.

Why: with labels, each point blends the extinction and emission of up to eight classes (the TFs
of its cell's corner labels, `volren.model.labels`), and each class's TF must be evaluated as
exactly as the plain reference evaluates its one TF (Real-Time Volume Graphics, section 16.2:
a transfer function per object): piecewise linear colour and opacity between control points,
constant beyond the ends, tau = -ln(1 - min(a, 1 - 1e-6)) / d_u with the class's own d_u.

How: every class's control points are concatenated into flat arrays with CSR offsets (class c's
colour points are colour_x[colour_offsets[c]:colour_offsets[c + 1]], and so on), so any number of
classes reaches a kernel as one named tuple of a fixed type; `class_sample` interpolates a class's
slices with `volren.kernels.tf_eval.interp`'s search rule (``x[k] <= s < x[k+1]``: duplicated
points make a step). `cuts` holds each class's `TransferFunction1D.linear_cuts` (between two of
them the class's colour, opacity and clamped opacity are linear in s), so that the integrator can
cut a ray where any class of a cell has a kink.

The label volume itself is turned into a class per grid point (`class_map`, -1 where hidden), so
labels that share a style share a class and their weights add up, which is exact: they have the
same tau and colour everywhere.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from volren.kernels.tf_eval import find_interval, interp
from volren.model.labels import LabelClasses, LabelMap
from volren.model.transfer_function import MAX_OPACITY, TransferFunction1D


class PackedClasses(NamedTuple):
    """The label classes' TFs as flat float64 arrays with CSR offsets (see the module docstring)."""

    color_offsets: NDArray[np.int64]
    color_x: NDArray[np.float64]
    color_rgb: NDArray[np.float64]
    opacity_offsets: NDArray[np.int64]
    opacity_x: NDArray[np.float64]
    opacity_a: NDArray[np.float64]
    #: each class's opacity_unit_distance
    units: NDArray[np.float64]
    cut_offsets: NDArray[np.int64]
    cuts: NDArray[np.float64]


def _offsets(counts: list[int]) -> NDArray[np.int64]:
    return np.concatenate([[0], np.cumsum(counts, dtype=np.int64)]).astype(np.int64)


def pack_classes(classes: LabelClasses) -> PackedClasses:
    """The classes' TFs as the kernels read them; a TF list may be empty (every label hidden)."""
    return pack_tfs(classes.tfs)


def pack_tfs(tfs: Sequence[TransferFunction1D]) -> PackedClasses:
    """Any list of 1D TFs (label classes, a channel each: `channels`) as `class_sample` reads them."""
    colors = [tf.color_points for tf in tfs]
    opacities = [tf.opacity_points for tf in tfs]
    cuts = [tf.linear_cuts() for tf in tfs]

    def stack(parts: list[NDArray], width: int) -> NDArray[np.float64]:
        if not parts:
            return np.zeros((0, width)) if width > 1 else np.zeros(0)
        return np.ascontiguousarray(np.concatenate(parts), dtype=np.float64)

    return PackedClasses(
        _offsets([len(c) for c in colors]),
        stack([c[:, 0] for c in colors], 1),
        stack([c[:, 1:4] for c in colors], 3),
        _offsets([len(o) for o in opacities]),
        stack([o[:, 0] for o in opacities], 1),
        stack([o[:, 1] for o in opacities], 1),
        np.array([tf.opacity_unit_distance for tf in tfs], dtype=np.float64),
        _offsets([len(c) for c in cuts]),
        stack(cuts, 1),
    )


def class_map(labels: LabelMap, lookup: NDArray[np.int32]) -> NDArray[np.int32]:
    """The class of every grid point ((z, y, x) like the values), -1 where its label is hidden
    (labels beyond the lookup table are hidden, as `LabelClasses` says)."""
    values = labels.values
    table = np.full(int(values.max()) + 1, -1, np.int32)
    n = min(len(lookup), len(table))
    table[:n] = lookup[:n]
    return np.ascontiguousarray(table[values])


@njit(nogil=True, cache=True)
def class_sample(classes, c, s):
    """(tau, r, g, b) of class c at the scalar s: its extinction per unit length and its colour."""
    a0 = classes.opacity_offsets[c]
    a1 = classes.opacity_offsets[c + 1]
    alpha = interp(classes.opacity_x[a0:a1], classes.opacity_a[a0:a1], s)
    alpha = min(max(alpha, 0.0), MAX_OPACITY)
    tau = -math.log1p(-alpha) / classes.units[c]
    c0 = classes.color_offsets[c]
    c1 = classes.color_offsets[c + 1]
    xs = classes.color_x[c0:c1]
    rgb = classes.color_rgb[c0:c1]
    n = c1 - c0
    if s <= xs[0]:
        return tau, rgb[0, 0], rgb[0, 1], rgb[0, 2]
    if s >= xs[n - 1]:
        return tau, rgb[n - 1, 0], rgb[n - 1, 1], rgb[n - 1, 2]
    k = find_interval(xs, s)
    w = (s - xs[k]) / (xs[k + 1] - xs[k])
    return (
        tau,
        rgb[k, 0] + (rgb[k + 1, 0] - rgb[k, 0]) * w,
        rgb[k, 1] + (rgb[k + 1, 1] - rgb[k, 1]) * w,
        rgb[k, 2] + (rgb[k + 1, 2] - rgb[k, 2]) * w,
    )
