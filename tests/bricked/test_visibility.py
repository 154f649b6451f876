"""The k-d order is the order in which every ray meets the bricks, under perspective and parallel
projection, with the eye outside or inside the grid."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from volren.bricked.layout import BrickLayout
from volren.bricked.visibility import front_to_back
from volren.model.camera import Camera


def bricks_along_rays(layout, origins, dirs, samples=400):
    """For every ray, the brick indices it passes through in order (sampled densely)."""
    b = np.asarray(layout.bounds)
    far = float(np.linalg.norm(b[1::2] - b[0::2])) + float(np.abs(origins).max()) * 2
    t = np.linspace(0.0, far, samples)
    edges = [layout.world_edges(a) for a in range(3)]
    sequences = []
    for o, d in zip(origins, dirs):
        p = o + t[:, None] * d
        inside = np.all((p >= b[0::2]) & (p < b[1::2]), axis=1)
        idx = [
            np.clip(np.searchsorted(edges[a], p[inside, a], side="right") - 1, 0, len(edges[a]) - 2)
            for a in range(3)
        ]
        seq = [(int(k), int(j), int(i)) for i, j, k in zip(*idx)]
        sequences.append([s for n, s in enumerate(seq) if n == 0 or s != seq[n - 1]])
    return sequences


@settings(max_examples=30, deadline=None)
@given(
    st.integers(2, 30),
    st.integers(2, 30),
    st.integers(2, 30),
    st.integers(2, 9),
    st.floats(-180, 180),
    st.floats(-80, 80),
    st.floats(0.5, 6.0),
    st.booleans(),
)
def test_every_ray_meets_the_bricks_in_the_order(nx, ny, nz, brick, azimuth, elevation, zoom, parallel):
    layout = BrickLayout((nx, ny, nz), (1.0, 0.8, 1.2), (0.0, -3.0, 1.0), (0.0, 1.0), brick)
    camera = Camera.orbit(layout.bounds, azimuth, elevation, zoom=zoom, parallel=parallel)
    order = front_to_back(layout, camera)
    assert sorted(order) == sorted(b.index for b in layout.bricks())
    position = {index: n for n, index in enumerate(order)}
    origins, dirs = camera.pixel_rays(12, 12)
    for seq in bricks_along_rays(layout, origins.reshape(-1, 3), dirs.reshape(-1, 3)):
        ranks = [position[s] for s in seq]
        assert ranks == sorted(ranks)


@settings(max_examples=30, deadline=None)
@given(
    st.tuples(*(st.floats(0.05, 0.95) for _ in range(3))),
    st.tuples(*(st.floats(-1, 1) for _ in range(3))),
    st.floats(20, 120),
)
def test_with_the_eye_inside_the_grid(place, look, angle):
    layout = BrickLayout((17, 13, 21), (1.0, 1.0, 1.0), (0.0, 0.0, 0.0), (0.0, 1.0), 4)
    b = np.asarray(layout.bounds)
    eye = b[0::2] + np.asarray(place) * (b[1::2] - b[0::2])
    look = np.asarray(look) if np.linalg.norm(look) > 0.1 else np.array([0.3, -0.2, 1.0])
    up = np.cross(look, [0.37, 0.59, 0.71])
    if np.linalg.norm(up) < 1e-3:
        up = np.cross(look, [1.0, 0.0, 0.0])
    camera = Camera(tuple(eye), tuple(eye + look), tuple(up), view_angle=angle, clipping_range=(0.01, 100.0))
    order = front_to_back(layout, camera)
    position = {index: n for n, index in enumerate(order)}
    origins, dirs = camera.pixel_rays(10, 10)
    for seq in bricks_along_rays(layout, origins.reshape(-1, 3), dirs.reshape(-1, 3)):
        ranks = [position[s] for s in seq]
        assert ranks == sorted(ranks)
