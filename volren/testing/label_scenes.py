"""The conformance kit's label scenes (`volren.model.labels`): a slab with a closed form and a
smooth field with three labels, one hidden and one in its own colour.

Why a slab: a label's weight is the trilinear interpolant of "the corner has this label", so across
the cell between the last hidden point and the first labelled one it ramps linearly from 0 to 1;
with a constant field the optical depth along a ray is then tau times the labelled length plus half
that cell (Real-Time Volume Graphics, section 16.5: the boundary between labels is filtered, not
stepped). A renderer that takes the nearest label instead misses or adds that half cell, and one
that ignores the labels draws the whole box.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from volren.model.labels import LabelMap, LabelStyle, LabelTransferFunction
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import UniformVolume
from volren.testing.scenes import lattice_points

#: The slab: its grid (points along x, y, z), spacing, the first labelled point along x, and the
#: colour, opacity and unit distance its label draws with. One whole labelled cell after the
#: boundary cell, each of optical depth 1.2: the boundary's half cell shows (nearest labels make
#: the alpha 0.70 or 0.91 instead of 0.84).
SLAB_DIMS = (8, 6, 7)
SLAB_SPACING = (0.8, 1.0, 1.1)
SLAB_FIRST = 6
SLAB_COLOUR = (0.2, 0.85, 0.4)
SLAB_OPACITY = 0.6
SLAB_UNIT = 0.6


def label_slab() -> tuple[UniformVolume, LabelTransferFunction]:
    """A constant field (0.5); label 1 at points i >= SLAB_FIRST, in its own colour, and the hidden
    label 0 below."""
    nx, ny, nz = SLAB_DIMS
    labels = np.zeros((nz, ny, nx), np.uint8)
    labels[:, :, SLAB_FIRST:] = 1
    volume = UniformVolume(np.full((nz, ny, nx), 0.5), spacing=SLAB_SPACING, origin=(1.0, -2.0, 0.5),
                           name="kit label slab", labels=LabelMap(labels))  # fmt: skip
    base = TransferFunction1D.constant(SLAB_OPACITY, (0.9, 0.9, 0.9), SLAB_UNIT)
    return volume, LabelTransferFunction(
        base, {0: LabelStyle(visible=False), 1: LabelStyle(color=SLAB_COLOUR)}
    )


def label_slab_rgba() -> NDArray[np.float64]:
    """The slab's premultiplied RGBA along any ray parallel to x through its inside: optical depth
    tau * dx * ((nx - 1 - SLAB_FIRST) + 1/2)."""
    tau = -math.log1p(-SLAB_OPACITY) / SLAB_UNIT
    alpha = -math.expm1(-tau * SLAB_SPACING[0] * ((SLAB_DIMS[0] - 1 - SLAB_FIRST) + 0.5))
    return np.array([*(c * alpha for c in SLAB_COLOUR), alpha])


def label_scene() -> tuple[UniformVolume, LabelTransferFunction]:
    """A smooth field on a 12 x 11 x 10 grid: label 1 (most points) draws with the volume's TF,
    label 2 (a ball) in its own colour and twice as opaque, label 3 (a block at one corner) hidden."""
    dims, spacing = (12, 11, 10), (0.9, 1.0, 1.1)
    pts = lattice_points(dims, spacing, (0.0, 0.0, 0.0))
    x, y, z = pts[:, 0], pts[:, 1], pts[:, 2]
    shape = dims[::-1]
    values = (np.sin(x) + np.cos(1.3 * y) + 0.5 * z).reshape(shape)
    labels = np.ones(len(pts), np.uint8)
    labels[(x - 5.0) ** 2 + (y - 5.5) ** 2 + (z - 4.5) ** 2 <= 3.3**2] = 2
    labels[(x > 6.5) & (y > 6.5) & (z > 4.0)] = 3
    volume = UniformVolume(values, spacing=spacing, name="kit labels", labels=LabelMap(labels.reshape(shape)))
    base = TransferFunction1D([[-2, 0.2, 0.3, 1.0], [4, 1.0, 0.8, 0.1]], [[-1, 0.0], [4, 0.5]], 1.0)
    styles = {2: LabelStyle(color=(1.0, 0.35, 0.1), opacity=2.0), 3: LabelStyle(visible=False)}
    return volume, LabelTransferFunction(base, styles)
