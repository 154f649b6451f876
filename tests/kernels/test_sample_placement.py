"""The shared midpoint rule against an explicit list of cut points, and the per-pixel phases."""

from __future__ import annotations

import numpy as np
import pytest

from volren.kernels.sample_placement import SLIVER, pixel_phases, ray_segment, ray_segments, segment_length


def explicit_segments(length: float, h: float, phase: float) -> list[tuple[float, float]]:
    """(start, length) of every segment: cuts at (phase + j) h from the start (phase 0: h, 2h, ...),
    the ray's end last; a piece below SLIVER * h adds no segment."""
    cuts = []
    c = phase * h if phase > 0.0 else h
    while c < length:
        cuts.append(c)
        c += h
    bounds = [0.0, *cuts, length]
    pieces = [(a, b - a) for a, b in zip(bounds[:-1], bounds[1:], strict=True)]
    return [p for p in pieces if p[1] > SLIVER * h] if length > SLIVER * h else []


# dyadic lengths, steps and phases: every cut and length is exact in binary
@pytest.mark.parametrize("length", [0.0, 0.125, 0.25, 0.375, 1.0, 1.125, 2.5, 3.0])
@pytest.mark.parametrize("h", [0.25, 0.5, 1.0])
@pytest.mark.parametrize("phase", [0.0, 0.25, 0.5, 0.75])
def test_segments_are_the_pieces_between_the_cuts(length, h, phase):
    expected = explicit_segments(length, h, phase)
    count, first, last = ray_segments(length, h, phase)
    assert count == len(expected)
    got = [ray_segment(0.0, first, last, h, count, k) for k in range(count)]
    assert got == expected
    assert [segment_length(first, last, h, count, k) for k in range(count)] == [p[1] for p in expected]


def test_a_sliver_past_a_cut_adds_no_segment():
    h = 0.5
    assert ray_segments(1.0 + 1e-3 * SLIVER * h, h, 0.0) == (2, 0.5, 0.5)
    assert ray_segments(0.5 * SLIVER * h, h, 0.0) == (0, 0.0, 0.0)


def test_pixel_phases():
    width, height = 5, 3
    np.testing.assert_array_equal(pixel_phases("midpoint", width, height, 7), np.zeros(15))
    expected = [0.0 if (i + j) % 2 == 0 else 0.5 for j in range(height) for i in range(width)]  # row 0 on top
    np.testing.assert_array_equal(pixel_phases("interleaved", width, height, 7), expected)
    np.testing.assert_array_equal(
        pixel_phases("random", width, height, 7), np.random.default_rng(7).random(15)
    )
