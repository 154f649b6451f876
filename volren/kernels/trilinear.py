"""The trilinear value of a grid at an index point, inside numba kernels, and the fast-math flags
that the sample kernels built on it compile with.

Why shared: a label volume's and a multi-channel volume's samples (`label_sample`,
`channel_sample`) read the scalar field the way every CPU ray caster does, and renderers that
share those samples must read the same value to give the same image.
"""

from __future__ import annotations

from numba import njit

#: numba's fast-math flags that keep non-finite values visible (they add nothing): fused
#: multiply-add, reciprocals, signed zeros, approximate functions. Not 'nnan' or 'ninf' (a NaN
#: sample must stay NaN to be dropped), nor 'reassoc' (with it NaN and Inf samples leaked into images).
FAST = {"contract", "nsz", "arcp", "afn"}


@njit(nogil=True, cache=True, inline="always", fastmath=FAST)
def trilinear_value(vol, px, py, pz):
    """Trilinear value of `vol` ((nz, ny, nx)) at index point (px, py, pz) inside the grid's box.
    Only the cell index is clamped (against rounding, and to keep every read inside the array): a
    caller's samples lie between its ray's entry and exit points, so the weights need no clamp and
    int() is the floor (in raycast's march the weights' clamps and a floor cost 5-12 % of a frame on
    the smooth TFs of bonsai and ironProt, interleaved in one process, and changed no pixel)."""
    nz, ny, nx = vol.shape
    i = max(min(int(px), nx - 2), 0)  # int() truncates: the floor for px >= 0
    j = max(min(int(py), ny - 2), 0)
    k = max(min(int(pz), nz - 2), 0)
    fx = px - i
    fy = py - j
    fz = pz - k
    v000, v001 = float(vol[k, j, i]), float(vol[k, j, i + 1])  # float(): 8-bit volumes stay 8-bit
    v010, v011 = float(vol[k, j + 1, i]), float(vol[k, j + 1, i + 1])
    v100, v101 = float(vol[k + 1, j, i]), float(vol[k + 1, j, i + 1])
    v110, v111 = float(vol[k + 1, j + 1, i]), float(vol[k + 1, j + 1, i + 1])
    x00 = v000 + fx * (v001 - v000)
    x10 = v010 + fx * (v011 - v010)
    x01 = v100 + fx * (v101 - v100)
    x11 = v110 + fx * (v111 - v110)
    y0 = x00 + fy * (x10 - x00)
    y1 = x01 + fy * (x11 - x01)
    return y0 + fz * (y1 - y0)
