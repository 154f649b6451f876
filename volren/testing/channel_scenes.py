"""The conformance kit's channel scenes (`volren.model.channels`): a constant two-channel slab with a
closed form and a smooth three-channel field.

Why a constant slab: the channels' densities add (Max 1995, section 2), so two constant media in one
box are one medium with the summed extinction tau = w0 tau0 + w1 tau1 and the emission-weighted
colour (w0 tau0 c0 + w1 tau1 c1) / tau: alpha = 1 - exp(-tau L) along a ray crossing a length L.
A renderer that draws one channel alone, ignores the weights or feeds one channel's scalar to
another's TF misses that alpha or colour.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from volren.model.channels import ChannelSet, ChannelTransferFunction
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import UniformVolume
from volren.testing.scenes import lattice_points

#: The slab: its grid (points along x, y, z), spacing, the two channels' constant values, and their
#: TFs' opacity and colour there (channel 0 a constant TF, channel 1 a ramp read at its middle),
#: unit distances and weights.
SLAB_DIMS = (7, 6, 5)
SLAB_SPACING = (0.5, 1.0, 1.1)
SLAB_VALUES = (0.5, 2.0)
SLAB_OPACITIES = (0.3, 0.4)
SLAB_COLOURS = ((0.0, 0.9, 0.2), (0.8, 0.1, 0.7))
SLAB_UNITS = (0.7, 1.2)
SLAB_WEIGHTS = (1.0, 1.5)


def channel_slab() -> tuple[UniformVolume, ChannelTransferFunction]:
    """A box of two constant channels (the volume's own values are channel 0's)."""
    nx, ny, nz = SLAB_DIMS
    shape = (nz, ny, nx)
    values = np.stack([np.full(shape, v) for v in SLAB_VALUES])
    volume = UniformVolume(values[0], spacing=SLAB_SPACING, origin=(1.0, -2.0, 0.5), name="kit channel slab",
                           channels=ChannelSet(values, names=("membrane", "nuclei")))  # fmt: skip
    first = TransferFunction1D.constant(SLAB_OPACITIES[0], SLAB_COLOURS[0], SLAB_UNITS[0])
    # a ramp 0 -> 4 whose middle (the channel's value 2) has SLAB_OPACITIES[1] and SLAB_COLOURS[1]
    c1 = np.asarray(SLAB_COLOURS[1])
    second = TransferFunction1D(
        [[0.0, *(c1 - 0.1)], [4.0, *(c1 + 0.1)]], [[0.0, 0.0], [4.0, 2.0 * SLAB_OPACITIES[1]]], SLAB_UNITS[1]
    )
    return volume, ChannelTransferFunction([first, second], SLAB_WEIGHTS)


def slab_extinctions() -> tuple[float, float]:
    """The two channels' weighted extinctions w_c tau_c in the slab."""
    a, b = (w * -math.log1p(-o) / u for w, o, u in zip(SLAB_WEIGHTS, SLAB_OPACITIES, SLAB_UNITS, strict=True))
    return a, b


def channel_slab_rgba(length: float | None = None) -> NDArray[np.float64]:
    """The slab's premultiplied RGBA along a ray crossing `length` of it (default: its whole x
    extent): one medium of the summed extinction, coloured by the channels' shares of it."""
    length = SLAB_SPACING[0] * (SLAB_DIMS[0] - 1) if length is None else length
    taus = slab_extinctions()
    alpha = -math.expm1(-sum(taus) * length)
    rgb = np.asarray(taus) @ np.asarray(SLAB_COLOURS) / sum(taus) * alpha
    return np.append(rgb, alpha)


def channel_scene() -> tuple[UniformVolume, ChannelTransferFunction]:
    """Three smooth channels on a 12 x 11 x 10 grid, overlapping: ramps in green, magenta and cyan,
    the third at weight 2 (the volume's own values are channel 0's)."""
    dims, spacing = (12, 11, 10), (0.9, 1.0, 1.1)
    pts = lattice_points(dims, spacing, (0.0, 0.0, 0.0))
    x, y, z = pts[:, 0], pts[:, 1], pts[:, 2]
    shape = dims[::-1]
    fields = [
        np.sin(x) + np.cos(1.3 * y) + 0.5 * z,
        np.exp(-((x - 5.0) ** 2 + (y - 5.5) ** 2 + (z - 4.5) ** 2) / 8.0),
        0.1 * x * y - 0.3 * z,
    ]
    values = np.stack([f.reshape(shape) for f in fields])
    volume = UniformVolume(values[0], spacing=spacing, name="kit channels", channels=ChannelSet(values))
    tfs = [
        TransferFunction1D([[-2, 0.0, 1.0, 0.0], [4, 0.3, 1.0, 0.3]], [[-1, 0.0], [4, 0.3]], 1.0),
        TransferFunction1D(
            [[0, 1.0, 0.0, 1.0], [1, 1.0, 0.5, 1.0]], [[0.2, 0.0], [0.6, 0.6], [1.0, 0.9]], 1.0
        ),
        TransferFunction1D([[-3, 0.0, 1.0, 1.0], [10, 0.0, 0.6, 1.0]], [[0, 0.0], [10, 0.2]], 1.0),
    ]
    return volume, ChannelTransferFunction(tfs, [1.0, 1.0, 2.0])
