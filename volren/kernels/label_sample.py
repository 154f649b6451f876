"""A label volume's sample in numba: a transfer function per label, blended across label boundaries.

Why its own classification: a label is not a number to interpolate. Each sample reads its cell's
class besides the scalar (`volren.model.labels.cell_classes`); where the cell's eight corners fall
in one class (the labels drawing with the same TF, `LabelTransferFunction.classes`), that class's
table classifies the sample exactly as a plain post-classified march does (the table interpolated
at the value, the opacity corrected to the segment's length), so a label scene whose labels all
draw alike gives the plain image. Where they differ, each class's extinction is weighted by the
trilinear weight of its corners (Real-Time Volume Graphics, section 16.5, boundary filtering;
`volren.model.labels`):

    tau h = sum_c W_c tau_c(s) h,   with tau_c h = -ln(1 - alpha_c(s)) from the class's table,

and the colour is the extinction-weighted mean of the classes' colours, so a boundary between two
labels blends their classified samples, not their label numbers, and a hidden class (tau 0) fades
its neighbour out over one cell instead of cutting it along voxel faces.

Shared by the CPU ray casters (raycast and the plugins), which each keep their own march around it.
"""

from __future__ import annotations

import math

from numba import njit

from volren.kernels.trilinear import FAST, trilinear_value
from volren.model.labels import MIXED
from volren.model.transfer_function import MAX_OPACITY


@njit(nogil=True, cache=True, inline="always", fastmath=FAST)
def _entry(post, c, fi, i0, w):
    """Class c's (r, g, b, alpha per step) at table position fi (entry i0, weight w)."""
    a = post[c, i0, 3] + w * (post[c, i0 + 1, 3] - post[c, i0, 3])
    r = post[c, i0, 0] + w * (post[c, i0 + 1, 0] - post[c, i0, 0])
    g = post[c, i0, 1] + w * (post[c, i0 + 1, 1] - post[c, i0, 1])
    b = post[c, i0, 2] + w * (post[c, i0 + 1, 2] - post[c, i0, 2])
    return r, g, b, a


@njit(nogil=True, cache=True, inline="always", fastmath=FAST)
def label_sample(vol, classes, px, py, pz, length):
    """Premultiplied (r, g, b, a) of a segment `length` long sampled at index point (px, py, pz):
    its cell's corner classes (`LabelClassification`) blended by their trilinear weights."""
    labels, lookup, post, h = classes.labels, classes.lookup, classes.post, classes.step
    s = trilinear_value(vol, px, py, pz)
    if not math.isfinite(s):
        return 0.0, 0.0, 0.0, 0.0
    nz, ny, nx = labels.shape
    i = max(min(int(px), nx - 2), 0)
    j = max(min(int(py), ny - 2), 0)
    k = max(min(int(pz), nz - 2), 0)
    n = post.shape[1]
    fi = min(max((s - classes.lo) * classes.scale, 0.0), n - 1.0)
    i0 = min(int(fi), n - 2)
    w = fi - i0
    c0 = classes.cells[k, j, i]
    if c0 != MIXED:  # the fast path: one class at all eight corners
        if c0 < 0:
            return 0.0, 0.0, 0.0, 0.0
        r, g, b, a = _entry(post, c0, fi, i0, w)
        if a <= 0.0:
            return 0.0, 0.0, 0.0, 0.0
        if length != h:
            a = -math.expm1(length / h * math.log1p(-min(a, MAX_OPACITY)))
        return r * a, g * a, b * a, a
    top = lookup.shape[0]
    fx = px - i
    fy = py - j
    fz = pz - k
    depth = 0.0  # tau h, summed over the corners' classes
    er = 0.0
    eg = 0.0
    eb = 0.0
    for q in range(8):
        label = int(labels[k + (q >> 2), j + ((q >> 1) & 1), i + (q & 1)])
        c = lookup[label] if label < top else -1
        if c < 0:
            continue
        wq = (fx if q & 1 else 1.0 - fx) * (fy if q & 2 else 1.0 - fy) * (fz if q & 4 else 1.0 - fz)
        if wq <= 0.0:
            continue
        r, g, b, a = _entry(post, c, fi, i0, w)
        if a <= 0.0:
            continue
        d = -wq * math.log1p(-min(a, MAX_OPACITY))
        depth += d
        er += d * r
        eg += d * g
        eb += d * b
    if depth <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    a = -math.expm1(-depth * (length / h))
    f = a / depth
    return er * f, eg * f, eb * f, a
