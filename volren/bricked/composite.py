"""Compositing premultiplied RGBA layers front to back ("over"), as every ray composites samples."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def over(front: NDArray, back: NDArray, out: NDArray | None = None) -> NDArray:
    """`back` seen through `front`: front + (1 - front alpha) back, per pixel (in place into `out`)."""
    result = front + (1.0 - front[..., 3:4]) * back
    if out is None:
        return result
    out[...] = result
    return out


def composite_front_to_back(layers: list[NDArray]) -> NDArray[np.float32]:
    """The layers, nearest first, composited into one float32 image (accumulated in float64)."""
    if not layers:
        raise ValueError("no layers to composite")
    acc = np.zeros(layers[0].shape, dtype=np.float64)
    for layer in layers:
        over(acc, layer.astype(np.float64, copy=False), out=acc)
    return acc.astype(np.float32)
