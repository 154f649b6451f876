"""`benchmarks.native_march`: both kernels draw each frame it times, and their images agree."""

from __future__ import annotations

import numpy as np

from benchmarks import native_march
from volren.renderers.raycast.march_native import kernels, numba_only, padded
from volren.testing.hard_cases import CASES


def test_both_kernels_draw_the_same_frames_and_the_counters_are_the_frames():
    case = CASES["hard_tubes"]
    row = native_march.compare(case.build(), case.tf(), frames=2, size=48)
    assert row["c_ms"] > 0 and row["numba_ms"] > 0
    assert row["diff"] <= 1e-3  # float rounding, or a ray stopping a segment earlier at opacity 0.999
    assert row["samples"] > 0 and row["skipped"] > 0 and row["rays"] == 48 * 48


def test_numba_only_holds_within_its_block_only():
    grid = padded(np.zeros((3, 3, 3), np.uint8))
    before = kernels(grid)
    with numba_only():
        assert kernels(grid) is None
    assert kernels(grid) == before


def test_the_2d_scenes_are_2d_tfs_both_kernels_draw_alike():
    from benchmarks.tf2d import two_d_tfs

    case = CASES["hard_tubes"]
    volume = case.build()
    tf = two_d_tfs(case.tf(), volume)["blob"]
    assert tf.dims == 2
    row = native_march.compare(volume, tf, frames=2, size=48)
    assert row["c_ms"] > 0 and row["numba_ms"] > 0
    assert row["diff"] <= 1e-3
    assert row["samples"] > 0 and row["rays"] == 48 * 48
