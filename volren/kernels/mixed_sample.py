"""One sample of a label or a multi-channel volume, chosen by its classification's type when numba
compiles: the march of a renderer that draws both is written once.

Why an overload: `LabelClassification` and `ChannelClassification` are different named tuples, so
numba compiles a march once per type; `sample_rgba` resolves to `label_sample` or `channel_sample`
inside that compilation, with no branch per sample.
"""

from __future__ import annotations

from numba import types
from numba.extending import overload

from volren.kernels.channel_sample import channel_sample
from volren.kernels.label_sample import label_sample
from volren.kernels.mixed_inputs import ChannelClassification, LabelClassification
from volren.kernels.trilinear import FAST


def sample_rgba(vol, classes, px, py, pz, length):  # type: ignore[no-untyped-def]
    """Premultiplied (r, g, b, a) of a segment `length` long at index point (px, py, pz): the
    label sample or the channel sample, chosen by the type of `classes` when numba compiles."""
    raise NotImplementedError("numba's: called from compiled kernels only")


@overload(sample_rgba, inline="always", jit_options={"fastmath": FAST})
def _sample_rgba(vol, classes, px, py, pz, length):  # type: ignore[no-untyped-def]
    kind = getattr(classes, "instance_class", None) if isinstance(classes, types.BaseNamedTuple) else None
    if kind is LabelClassification:
        return lambda vol, classes, px, py, pz, length: label_sample(vol, classes, px, py, pz, length)
    if kind is ChannelClassification:
        return lambda vol, classes, px, py, pz, length: channel_sample(vol, classes, px, py, pz, length)
    return None
