"""Entry faces binned to pixels: per row block and per sparse pixel set through tiles give the same
lists, and both equal a brute-force test of every pixel against every triangle."""

from __future__ import annotations

import numpy as np
import pytest

from volren.kernels.tet_projection import pixel_coordinates
from volren.model.camera import Camera
from volren.renderers.tetra.entry_bins import (
    MARGIN,
    bin_tiles,
    bin_triangles,
    bin_triangles_at,
    project_faces,
)

WIDTH, HEIGHT = 37, 29


def _scene(seed: int):
    """Random projected triangles: small and large, partly and wholly off screen, flat ones, one
    with a vertex behind the eye and one with a non-finite vertex."""
    rng = np.random.default_rng(seed)
    n_points = 60
    px = rng.uniform(-10, WIDTH + 10, n_points)
    py = rng.uniform(-10, HEIGHT + 10, n_points)
    px[:20] = rng.uniform(0, WIDTH, 20)
    py[:20] = rng.uniform(0, HEIGHT, 20)
    behind = np.zeros(n_points, dtype=bool)
    behind[55] = True
    px[56] = np.inf
    tris = [rng.choice(50, 3, replace=False) for _ in range(40)]
    # small triangles around random points, a flat one (collinear), and the special vertices
    for k in range(20):
        tris.append(np.array([k, (k + 1) % 20, (k + 7) % 20]))
    px[50:53] = (3.0, 9.0, 15.0)
    py[50:53] = (4.0, 4.0, 4.0)
    tris += [np.array([50, 51, 52]), np.array([1, 2, 55]), np.array([3, 4, 56])]
    triangles = np.array(tris, dtype=np.int64)
    cells = rng.permutation(len(triangles)) + 1000
    return project_faces(px, py, behind, triangles, cells, WIDTH, HEIGHT), px, py, behind, triangles, cells


def _brute_force(px, py, behind, triangles, cells, x, y):
    """The cells listed at pixel centre (x, y), in triangle order, tested directly."""
    out = []
    for tri, cell in zip(triangles, cells, strict=True):
        if behind[tri].any():
            out.append(cell)
            continue
        vx, vy = px[tri], py[tri]
        if not np.isfinite(vx).all() or not np.isfinite(vy).all():
            continue
        if not (vx.min() - MARGIN <= x <= vx.max() + MARGIN and vy.min() - MARGIN <= y <= vy.max() + MARGIN):
            continue
        area = (vx[1] - vx[0]) * (vy[2] - vy[0]) - (vy[1] - vy[0]) * (vx[2] - vx[0])
        sign = 1.0 if area >= 0 else -1.0
        inside = True
        for e in range(3):
            ux, uy, wx, wy = vx[e], vy[e], vx[(e + 1) % 3], vy[(e + 1) % 3]
            length = np.hypot(wx - ux, wy - uy)
            if length > 0 and sign * ((wx - ux) * (y - uy) - (wy - uy) * (x - ux)) / length < -MARGIN:
                inside = False
        if inside:
            out.append(cell)
    return out


@pytest.mark.parametrize("seed", range(4))
def test_row_blocks_match_brute_force(seed: int) -> None:
    faces, px, py, behind, triangles, cells = _scene(seed)
    offsets, cand = bin_triangles(faces, 0, HEIGHT)
    assert len(offsets) == WIDTH * HEIGHT + 1
    listed = 0
    for p in range(WIDTH * HEIGHT):
        expected = _brute_force(px, py, behind, triangles, cells, p % WIDTH, p // WIDTH)
        assert list(cand[offsets[p] : offsets[p + 1]]) == expected, p
        listed += len(expected)
    assert listed > WIDTH * HEIGHT  # the scene does cover pixels, many of them twice
    # a block of rows lists the same as those rows of the whole image
    o2, c2 = bin_triangles(faces, 7, 19)
    a, b = 7 * WIDTH, 19 * WIDTH
    assert np.array_equal(o2, offsets[a : b + 1] - offsets[a])
    assert np.array_equal(c2, cand[offsets[a] : offsets[b]])


@pytest.mark.parametrize("tile", [1, 4, 8, 64])
@pytest.mark.parametrize("seed", range(3))
def test_sparse_pixels_through_tiles_match_row_blocks(seed: int, tile: int) -> None:
    faces, *_ = _scene(seed)
    offsets, cand = bin_triangles(faces, 0, HEIGHT)
    rng = np.random.default_rng(100 + seed)
    for count in (1, 17, WIDTH * HEIGHT):
        pixels = np.sort(rng.choice(WIDTH * HEIGHT, count, replace=False)).astype(np.int64)
        o, c = bin_triangles_at(faces, bin_tiles(faces, tile), pixels, tile)
        assert len(o) == count + 1
        for j, p in enumerate(pixels):
            assert np.array_equal(c[o[j] : o[j + 1]], cand[offsets[p] : offsets[p + 1]])


def test_tiles_hold_exactly_the_faces_whose_box_meets_them() -> None:
    faces, *_ = _scene(0)
    tile = 8
    offsets, members = bin_tiles(faces, tile)
    tiles_x, tiles_y = -(-WIDTH // tile), -(-HEIGHT // tile)
    assert len(offsets) == tiles_x * tiles_y + 1
    for b in range(tiles_x * tiles_y):
        bx, by = b % tiles_x, b // tiles_x
        expected = [
            i
            for i, (_, x0, x1, y0, y1) in enumerate(faces.boxes)
            if x0 <= x1
            and y0 <= y1
            and x0 <= bx * tile + tile - 1
            and x1 >= bx * tile
            and y0 <= by * tile + tile - 1
            and y1 >= by * tile
        ]
        assert list(members[offsets[b] : offsets[b + 1]]) == expected


def test_pixel_coordinates_follow_the_camera() -> None:
    """The focal point projects to the image centre; points along a pixel's ray project to that
    pixel's centre; a point behind the eye is flagged."""
    camera = Camera(position=(1.0, 2.0, 9.0), focal_point=(0.5, 0.0, 0.0), view_up=(0.0, 1.0, 0.2))
    origins, dirs = camera.rays(WIDTH, HEIGHT, np.array([3, 30]), np.array([5, 20]))
    points = np.concatenate(
        [
            [camera.focal_point],
            origins + 2.0 * dirs,
            origins + 7.5 * dirs,
            [2.0 * np.array(camera.position) - camera.focal_point],
        ]
    )
    px, py, w = pixel_coordinates(camera, WIDTH, HEIGHT, points)
    assert np.allclose([px[0], py[0]], [(WIDTH - 1) / 2, (HEIGHT - 1) / 2], atol=1e-9)
    assert np.allclose(px[1:5], [3, 30, 3, 30], atol=1e-9) and np.allclose(py[1:5], [5, 20, 5, 20], atol=1e-9)
    assert list(w > 0) == [True] * 5 + [False]


def test_special_faces() -> None:
    """A face behind the eye covers every pixel; a non-finite one none; boxes stay in the image."""
    faces, *_ = _scene(1)
    whole, nonfinite = len(faces.boxes) - 2, len(faces.boxes) - 1
    assert tuple(faces.boxes[whole]) == (1, 0, WIDTH - 1, 0, HEIGHT - 1)
    assert faces.boxes[nonfinite, 1] > faces.boxes[nonfinite, 2]
    valid = faces.boxes[:, 1] <= faces.boxes[:, 2]
    assert (faces.boxes[valid, 1] >= 0).all() and (faces.boxes[valid, 2] < WIDTH).all()
    assert np.isfinite(faces.edges).all()
