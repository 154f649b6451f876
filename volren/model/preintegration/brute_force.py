"""The same tables by brute force, O(n^2 n_t): every entry composites its bins one by one.

Why: a plainly correct float64 definition of what `subrange` computes (same bins, same
per-bin model, same ramp), for tests and the benchmark. The lighting weights are applied
directly, w = (g - i) / (j - i), not through the global-ramp difference.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from volren.model.preintegration.segment_math import emission_centre


@njit(nogil=True, parallel=True, cache=True)
def brute_force_tables(tau, color, m, n, lengths, weighted, out, out_back):
    """Same contract as `subrange.subrange_tables`, computed in float64 entry by entry."""
    nlen = lengths.shape[0]
    for task in prange(nlen * n):
        li = task // n
        i = task % n
        for j in range(n):
            if j == i:
                continue
            r = abs(j - i)
            ell = lengths[li] / (r * m)
            step = 1 if j > i else -1
            k = i * m if j > i else i * m - 1
            t = 1.0
            c = np.zeros(3)
            bc = np.zeros(3)
            bw = 0.0
            for _ in range(r * m):
                x = tau[k] * ell
                a = -math.expm1(-x)
                if weighted:
                    u = emission_centre(x)
                    g = (k + u) / m if j > i else (k + 1 - u) / m
                    wgt = (g - i) / (j - i)
                    bw += wgt * t * a
                for ch in range(3):
                    v = t * color[k, ch] * a
                    c[ch] += v
                    if weighted:
                        bc[ch] += wgt * v
                t *= math.exp(-x)
                k += step
            alpha = 1.0 - t
            out[li, i, j, 3] = alpha
            for ch in range(3):
                v = min(c[ch], alpha)
                out[li, i, j, ch] = v
                if weighted:
                    out_back[li, i, j, ch] = min(max(bc[ch], 0.0), v)
            if weighted:
                out_back[li, i, j, 3] = min(max(bw, 0.0), alpha)
