"""Scalar helpers shared by the table kernels: one homogeneous bin of a segment.

A bin of mean extinction tau crossed over a length l has optical depth x = tau l, transmittance
exp(-x), opacity -expm1(-x) (accurate for thin bins) and emits its colour times that opacity.
Its light leaves the bin's front as if emitted at the fraction `emission_centre(x)` of the way
in: 1/2 for a thin bin, nearer the front for a thick one. The lighting tables use that point as
the bin's position on the front-to-back ramp, which makes their weights exact for homogeneous
bins.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(nogil=True, cache=True)
def emission_centre(x):
    """1/x - 1/(exp(x) - 1): the attenuation-weighted mean depth of emission, as a fraction."""
    if x < 1e-3:
        return 0.5 - x / 12.0 + x * x * x / 720.0
    return 1.0 / x - 1.0 / math.expm1(x)


@njit(nogil=True, cache=True)
def emission_centres(depths):
    """`emission_centre` of every optical depth in a float64 array (any shape)."""
    out = np.empty_like(depths)
    flat_in = depths.ravel()
    flat_out = out.ravel()
    for k in range(flat_in.shape[0]):
        flat_out[k] = emission_centre(flat_in[k])
    return out
