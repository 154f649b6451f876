"""`clip_to_planes` against the kept region sampled along each ray."""

from __future__ import annotations

import numpy as np

from volren.kernels.clip_planes import clip_to_planes


def test_the_interval_is_where_sampled_points_are_kept():
    rng = np.random.default_rng(11)
    for _ in range(300):
        planes = rng.normal(size=(rng.integers(1, 5), 4))
        o = rng.normal(size=3)
        d = rng.normal(size=3)
        t0, t1 = clip_to_planes(*o, *d, planes, -3.0, 3.0)
        ts = np.linspace(-3.0, 3.0, 4001)
        points = o + ts[:, None] * d
        kept = np.all(points @ planes[:, :3].T + planes[:, 3] >= 0, axis=1)
        if t1 <= t0:
            assert not kept[1:-1].any()
            continue
        inside = (ts > t0 + 1e-9) & (ts < t1 - 1e-9)
        outside = (ts < t0 - 1e-9) | (ts > t1 + 1e-9)
        assert kept[inside].all() and not kept[outside].any()


def test_a_ray_parallel_to_a_plane_is_kept_whole_or_lost_whole():
    plane = np.array([[0.0, 0.0, 1.0, -2.0]])  # keeps z >= 2
    assert clip_to_planes(0.0, 0.0, 3.0, 1.0, 0.0, 0.0, plane, 0.0, 5.0) == (0.0, 5.0)
    t0, t1 = clip_to_planes(0.0, 0.0, 1.0, 1.0, 0.0, 0.0, plane, 0.0, 5.0)
    assert t1 <= t0


def test_no_planes_leave_the_interval_as_it_was():
    assert clip_to_planes(0.0, 0.0, 0.0, 1.0, 0.0, 0.0, np.zeros((0, 4)), 0.5, 2.5) == (0.5, 2.5)


def test_the_entering_plane_is_the_one_that_moved_the_entry_last():
    from volren.kernels.clip_planes import clip_entry

    planes = np.array(
        [[1.0, 0.0, 0.0, -1.0], [1.0, 0.0, 0.0, -2.0], [-1.0, 0.0, 0.0, 5.0]]
    )  # x >= 1, x >= 2, x <= 5
    assert clip_entry(0.0, 0.0, 0.0, 1.0, 0.0, 0.0, planes, 0.0, 10.0) == (2.0, 5.0, 1)
    assert clip_entry(0.0, 0.0, 0.0, 1.0, 0.0, 0.0, planes, 3.0, 10.0) == (
        3.0,
        5.0,
        -1,
    )  # entered before the planes
    assert clip_entry(9.0, 0.0, 0.0, -1.0, 0.0, 0.0, planes, 0.0, 10.0) == (4.0, 7.0, 2)
