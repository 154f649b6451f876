"""Engel, Kraus and Ertl's approximate table from integral functions (Real-Time Volume Graphics, section 4.5), O(n^2).

The opacity uses the integral function of the extinction and is exact (the optical depth of a
segment is the step times the mean extinction over its value span). The colour C = step * mean(q)
drops the attenuation inside the segment, so it exceeds the opacity when the segment is thick:
for a homogeneous segment of optical depth x, C / (c alpha) = x / (1 - exp(-x)) (1.05 at x = 0.1,
1.58 at x = 1). Colour channels are clamped to 1, not to the opacity, so that this shows. Kept
for comparison with the exact table (benchmark and tests), not used by renderers.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange


@njit(nogil=True, parallel=True, cache=True)
def integral_function_table(tau, color, m, n, step, diag_tau, diag_color, out):
    """out (n, n, 4) float32 from the TF's bin means (nb = m (n - 1)) and its point values on the
    diagonal."""
    nb = tau.shape[0]
    cum_t = np.zeros(nb + 1)
    cum_q = np.zeros((nb + 1, 3))
    for k in range(nb):
        cum_t[k + 1] = cum_t[k] + tau[k]
        for c in range(3):
            cum_q[k + 1, c] = cum_q[k, c] + tau[k] * color[k, c]
    for i in prange(n):
        for j in range(n):
            if i == j:
                mean_t = diag_tau[i]
            else:
                mean_t = (cum_t[j * m] - cum_t[i * m]) / ((j - i) * m)
            out[i, j, 3] = -math.expm1(-step * mean_t)
            for c in range(3):
                if i == j:
                    mean_q = diag_tau[i] * diag_color[i, c]
                else:
                    mean_q = (cum_q[j * m, c] - cum_q[i * m, c]) / ((j - i) * m)
                out[i, j, c] = min(max(step * mean_q, 0.0), 1.0)
