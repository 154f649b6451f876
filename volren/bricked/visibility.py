"""The front-to-back order of a brick grid's bricks for a camera.

Why a k-d traversal: split the grid by one plane of brick faces; every ray from the eye that
crosses the plane goes from the eye's side to the other, so everything on the eye's side comes
first along it. Applied recursively, this orders the bricks for every ray at once, under
perspective (the eye's position decides) and parallel projection (the view direction decides).
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
from numpy.typing import NDArray

from volren.bricked.layout import BrickLayout, Index3
from volren.model.camera import Camera


def _split(
    lo: list[int], hi: list[int]
) -> tuple[int, int, tuple[list[int], list[int]], tuple[list[int], list[int]]]:
    """The k-d split of brick range [lo, hi) (x, y, z): the axis with most bricks, at its middle;
    (axis, cut, low half, high half). Every traversal and partition here uses this one rule, so
    a block of `kd_blocks` is a subtree of `front_to_back`'s traversal."""
    counts = [hi[a] - lo[a] for a in range(3)]
    axis = int(np.argmax(counts))
    cut = lo[axis] + counts[axis] // 2
    low_hi = list(hi)
    low_hi[axis] = cut
    high_lo = list(lo)
    high_lo[axis] = cut
    return axis, cut, (lo, low_hi), (high_lo, hi)


def front_to_back(layout: BrickLayout, camera: Camera) -> list[Index3]:
    """Every brick index (bk, bj, bi), nearest first, valid for every ray of `camera`."""
    eye = np.asarray(camera.position, dtype=np.float64)
    direction = np.asarray(camera.direction, dtype=np.float64)
    edges = [layout.world_edges(axis) for axis in range(3)]

    def low_side_first(axis: int, cut: int) -> bool:
        if camera.parallel:
            return bool(direction[axis] >= 0.0)
        return bool(eye[axis] <= edges[axis][cut])

    def visit(lo: list[int], hi: list[int]) -> Iterator[Index3]:
        if all(hi[a] - lo[a] == 1 for a in range(3)):
            yield (lo[2], lo[1], lo[0])
            return
        axis, cut, low, high = _split(lo, hi)
        halves = [low, high] if low_side_first(axis, cut) else [high, low]
        for a, b in halves:
            yield from visit(a, b)

    bz, by, bx = layout.shape
    return list(visit([0, 0, 0], [bx, by, bz]))


def kd_blocks(layout: BrickLayout, count: int) -> NDArray[np.intp]:
    """Per brick (bz, by, bx), which of about `count` spatial blocks it belongs to: the subtrees
    of `front_to_back`'s k-d tree, split until there are `count` (or every block is one brick).

    Why: a block's bricks come one after another in the front-to-back order of every camera,
    so whoever holds a block (a cluster worker) can composite its bricks into one layer, and the
    layers composite in block order.
    """
    blocks = np.zeros(layout.shape, dtype=np.intp)
    bz, by, bx = layout.shape
    pending = [([0, 0, 0], [bx, by, bz])]
    while len(pending) < count:
        # split the block with the most bricks next, so that blocks stay about equal
        sizes = [np.prod([h - lo_ for lo_, h in zip(lo, hi, strict=True)]) for lo, hi in pending]
        largest = int(np.argmax(sizes))
        if sizes[largest] <= 1:
            break
        lo, hi = pending.pop(largest)
        _, _, low, high = _split(lo, hi)
        pending[largest:largest] = [low, high]
    for n, (lo, hi) in enumerate(pending):
        blocks[lo[2] : hi[2], lo[1] : hi[1], lo[0] : hi[0]] = n
    return blocks
