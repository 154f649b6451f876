"""A multi-channel volume's sample in numba: each channel's TF at its own trilinear value, the
channels' extinctions and emissions added (`volren.model.channels`, Max 1995).

Why tables of depth, not of opacity: the channels mix by adding their extinctions, so each
channel's table holds (r, g, b, w tau h) at evenly spaced values (its weight w folded in), and a
sample's opacity is 1 - exp(-sum of the depths) once, where tables of opacity would need a
logarithm per channel and sample. Shared by the CPU ray casters, which each keep their own march.
"""

from __future__ import annotations

import math

from numba import njit

from volren.kernels.trilinear import FAST, trilinear_value


@njit(nogil=True, cache=True, inline="always", fastmath=FAST)
def channel_sample(vol, classes, px, py, pz, length):
    """Premultiplied (r, g, b, a) of a segment `length` long sampled at index point (px, py, pz):
    every channel of the `ChannelClassification` looked up at its own value, depths added. A
    channel whose value is not finite there adds nothing. `vol` is not read (the channels are the
    field): it keeps the signature of `label_sample`."""
    channels, post, lo, scale = classes.channels, classes.post, classes.lo, classes.scale
    n = post.shape[1]
    depth = 0.0
    er = 0.0
    eg = 0.0
    eb = 0.0
    for c in range(channels.shape[0]):
        s = trilinear_value(channels[c], px, py, pz)
        if not math.isfinite(s):
            continue
        fi = min(max((s - lo[c]) * scale[c], 0.0), n - 1.0)
        i0 = min(int(fi), n - 2)
        w = fi - i0
        d = post[c, i0, 3] + w * (post[c, i0 + 1, 3] - post[c, i0, 3])
        if d <= 0.0:
            continue
        depth += d
        er += d * (post[c, i0, 0] + w * (post[c, i0 + 1, 0] - post[c, i0, 0]))
        eg += d * (post[c, i0, 1] + w * (post[c, i0 + 1, 1] - post[c, i0, 1]))
        eb += d * (post[c, i0, 2] + w * (post[c, i0 + 1, 2] - post[c, i0, 2]))
    if depth <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    a = -math.expm1(-depth * (length / classes.step))
    f = a / depth
    return er * f, eg * f, eb * f, a
