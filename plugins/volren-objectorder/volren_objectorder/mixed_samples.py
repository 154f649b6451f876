"""A label or multi-channel volume's samples inside the object-order walk, chosen when numba compiles.

Why a compile-time choice: the walk (`composite`) is one kernel for every frame; a label volume's
sample blends the TFs of its cell's corner labels and a multi-channel volume's adds every channel's
(the shared kernels `volren.kernels.label_sample`, `volren.kernels.channel_sample`, Real-Time Volume
Graphics section 16.5 and Max 1995). The walk takes the frame's classification as one more
argument: a `LabelClassification`, a `ChannelClassification`, or `PLAIN` (a 1D TF's frame). numba
compiles the walk once per type, `is_mixed` is a constant in each, and the plain walk keeps its own
samples and speed (the mixed branch is dead code there and dropped).
"""

from __future__ import annotations

from typing import NamedTuple

from numba import types
from numba.extending import overload

from volren.kernels.mixed_inputs import ChannelClassification, LabelClassification
from volren.kernels.mixed_sample import sample_rgba


class NoClasses(NamedTuple):
    """A 1D TF's frame: no label or channel classification (the walk's `classes` argument)."""

    unused: int


#: What the walk takes as `classes` for a frame of a 1D TF.
PLAIN = NoClasses(0)


def _kind(classes: types.Type) -> type | None:
    return getattr(classes, "instance_class", None) if isinstance(classes, types.BaseNamedTuple) else None


def is_mixed(classes):  # type: ignore[no-untyped-def]
    """Whether `classes` is a label or channel classification (a constant when numba compiles)."""
    raise NotImplementedError("numba's: called from compiled kernels only")


def mixed_rgba(vol, classes, px, py, pz, length):  # type: ignore[no-untyped-def]
    """Premultiplied (r, g, b, a) of a segment `length` long at index point (px, py, pz) of a label
    or multi-channel volume (`volren.kernels.mixed_sample.sample_rgba`); transparent for `PLAIN`,
    whose walk never calls it."""
    raise NotImplementedError("numba's: called from compiled kernels only")


@overload(is_mixed, inline="always")
def _is_mixed(classes):  # type: ignore[no-untyped-def]
    if _kind(classes) in (LabelClassification, ChannelClassification):
        return lambda classes: True
    return lambda classes: False


@overload(mixed_rgba, inline="always")
def _mixed_rgba(vol, classes, px, py, pz, length):  # type: ignore[no-untyped-def]
    if _kind(classes) in (LabelClassification, ChannelClassification):
        return lambda vol, classes, px, py, pz, length: sample_rgba(vol, classes, px, py, pz, length)
    return lambda vol, classes, px, py, pz, length: (0.0, 0.0, 0.0, 0.0)
