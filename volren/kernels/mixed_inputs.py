"""What a label or a multi-channel volume's sample reads (`label_sample`, `channel_sample`), as
named tuples numba passes to a kernel as one parameter.

Why a module of their own, with numpy only: a renderer builds these before it knows which march
draws the frame, and raycast's C march draws without importing numba (its import costs a one-shot
render about a second).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

__all__ = ["ChannelClassification", "LabelClassification"]


class LabelClassification(NamedTuple):
    """How a label volume's segment gets its colour (`label_sample`): the classes of its cell's
    corner labels (`LabelTransferFunction.classes`), each post-classified from its own table."""

    #: (nz, ny, nx) uint8 or uint16 labels on the values' grid
    labels: NDArray[Any]
    #: label -> class (-1: hidden); labels past its end are hidden
    lookup: NDArray[np.int32]
    #: each cell's class where its corners share one, else `volren.model.labels.MIXED`
    #: (`volren.model.labels.cell_classes`: (nz, ny, nx) at the cell's first corner)
    cells: NDArray[np.int16]
    #: (classes, n, 4) colour and opacity per step at n values evenly spaced from lo
    post: NDArray[np.float64]
    #: the step h
    step: float
    #: a value s sits at table entry (s - lo) * scale
    lo: float
    scale: float


class ChannelClassification(NamedTuple):
    """How a multi-channel volume's segment gets its colour (`channel_sample`): every drawn channel
    looked up at its own value in its own table, the depths added."""

    #: (channels, nz, ny, nx): the drawn channels, in the values' type (8-bit or float32)
    channels: NDArray[Any]
    #: (channels, n, 4): colour and depth w tau h per step at n values evenly spaced from lo[c]
    post: NDArray[np.float64]
    #: the step h
    step: float
    #: channel c's value s sits at entry (s - lo[c]) * scale[c] of its table
    lo: NDArray[np.float64]
    scale: NDArray[np.float64]
