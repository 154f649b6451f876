"""The front-to-back order of a brick grid's bricks for a camera.

Why a k-d traversal: split the grid by one plane of brick faces; every ray from the eye that
crosses the plane goes from the eye's side to the other, so everything on the eye's side comes
first along it. Applied recursively, this orders the bricks for every ray at once, under
perspective (the eye's position decides) and parallel projection (the view direction decides).
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from volren.bricked.layout import BrickLayout, Index3
from volren.model.camera import Camera


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
        counts = [hi[a] - lo[a] for a in range(3)]
        if max(counts) == 1:
            yield (lo[2], lo[1], lo[0])
            return
        axis = int(np.argmax(counts))
        cut = lo[axis] + counts[axis] // 2
        low_hi = list(hi)
        low_hi[axis] = cut
        high_lo = list(lo)
        high_lo[axis] = cut
        halves = [(lo, low_hi), (high_lo, hi)]
        if not low_side_first(axis, cut):
            halves.reverse()
        for a, b in halves:
            yield from visit(a, b)

    bz, by, bx = layout.shape
    return list(visit([0, 0, 0], [bx, by, bz]))
