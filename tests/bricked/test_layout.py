"""Bricks partition the whole grid: every cell and every point of the box belongs to exactly one
brick, ghost voxels stay inside the grid, and regions carry the whole volume's box and range."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from volren.bricked.layout import BrickLayout
from volren.errors import VolrenError
from volren.model.region import Region

dims = st.tuples(*(st.integers(2, 40) for _ in range(3)))


def layout_of(dimensions, brick, spacing=(0.7, 1.3, 1.0), origin=(-2.0, 0.5, 3.0)):
    return BrickLayout(dimensions, spacing, origin, (0.0, 1.0), brick)


@settings(max_examples=60, deadline=None)
@given(dims, st.integers(1, 17))
def test_bricks_partition_the_cells(dimensions, brick):
    layout = layout_of(dimensions, brick)
    count = np.zeros(tuple(n - 1 for n in dimensions[::-1]), dtype=int)
    for b in layout.bricks():
        assert all(0 <= f < e <= n - 1 for f, e, n in zip(b.first, b.end, dimensions))
        assert all(e - f <= brick for f, e in zip(b.first, b.end))
        count[b.first[2] : b.end[2], b.first[1] : b.end[1], b.first[0] : b.end[0]] += 1
    assert count.min() == 1 and count.max() == 1
    assert layout.n_bricks == len(list(layout.bricks()))


@settings(max_examples=40, deadline=None)
@given(dims, st.integers(1, 9), st.integers(0, 4), st.integers(0, 2**31 - 1))
def test_every_point_of_the_box_belongs_to_one_region(dimensions, brick, ghost, seed):
    layout = layout_of(dimensions, brick)
    b = np.asarray(layout.bounds)
    rng = np.random.default_rng(seed)
    points = b[0::2] + rng.random((300, 3)) * (b[1::2] - b[0::2])
    # points on the faces between bricks and on the whole box's faces too
    edges = [layout.world_edges(a) for a in range(3)]
    for a in range(3):
        points[:100, a] = rng.choice(edges[a], 100)
    owners = np.zeros(len(points), dtype=int)
    for brick_ in layout.bricks():
        region = layout.region(brick_)
        assert region.whole_bounds == layout.bounds and region.value_range == (0.0, 1.0)
        inside = region.owns(points)
        owners += inside
        # the brick's sub-volume (with ghosts) covers its owned points
        sl = layout.voxel_slices(brick_, ghost)
        lo = np.asarray(layout.sub_origin(sl))
        n = np.array([sl[2].stop - sl[2].start, sl[1].stop - sl[1].start, sl[0].stop - sl[0].start])
        hi = lo + np.asarray(layout.spacing) * (n - 1)
        assert np.all(points[inside] >= lo - 1e-9) and np.all(points[inside] <= hi + 1e-9)
        for s, axis in zip(sl, (2, 1, 0)):
            assert 0 <= s.start and s.stop <= dimensions[axis]
            assert s.start == max(brick_.first[axis] - ghost, 0)
            assert s.stop - 1 == min(brick_.end[axis] + ghost, dimensions[axis] - 1)
    assert np.all(owners == 1)


def test_bad_layouts_and_regions_are_one_line_errors():
    with pytest.raises(VolrenError, match="at least 1 cell"):
        layout_of((5, 5, 5), 0)
    with pytest.raises(VolrenError, match="min < max"):
        Region((0, 0, 0), (1, 0, 1), (0, 1, 0, 1, 0, 1), (0, 1))
    with pytest.raises(VolrenError, match="finite"):
        Region((0, 0, 0), (1, np.nan, 1), (0, 1, 0, 1, 0, 1), (0, 1))
