"""Picking a label in the view (`volren.app.core.label_picking`), without Qt, against a brute-force
oracle: every ray walked in steps of a thousandth of a voxel, each step taking the label of its
nearest grid point.

The scene: a 33^3 grid (spacing 1) of constant value 1; label 1 fills the slab |z - 16| <= 5 over
4 <= x, y <= 28, and a ball of label 3 (radius 5, centre (16, 16, 16)) sits inside it, as thick as
the slab on its axis; label 0 (the background) is hidden. Seen along -z with a parallel camera.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from volren.app.core.label_picking import pick_label, voxel_pieces
from volren.app.core.picking import pixel_ray
from volren.kernels.tet_projection import ray_far
from volren.model.camera import Camera
from volren.model.labels import LabelMap, LabelStyle, LabelTransferFunction
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import UniformVolume

N = 33
C = 16
R = 5
SIZE = 65


def _scene() -> tuple[UniformVolume, LabelTransferFunction, Camera]:
    k, j, i = np.mgrid[0:N, 0:N, 0:N]
    labels = np.zeros((N, N, N), np.uint8)
    labels[(abs(k - C) <= R) & (i >= 4) & (i <= 28) & (j >= 4) & (j <= 28)] = 1
    labels[(i - C) ** 2 + (j - C) ** 2 + (k - C) ** 2 <= R * R] = 3
    volume = UniformVolume(np.ones((N, N, N), np.float32), labels=LabelMap(labels))
    base = TransferFunction1D(np.array([[0.0, 1, 1, 1], [1.0, 1, 1, 1]]), np.array([[0.0, 0.0], [1.0, 0.5]]))
    label_tf = LabelTransferFunction(base, {0: LabelStyle(visible=False)})
    camera = Camera.orbit(volume.bounds, 0.0, 0.0, 1.0, True, 1.0)
    return volume, label_tf, camera


def _brute_force(
    volume: UniformVolume, label_tf: LabelTransferFunction, camera: Camera, x: int, y: int
) -> int | None:
    """The label of the first step (1e-3 voxel) whose nearest grid point's label is drawn, on the ray
    of `Camera.pixel_rays` through pixel (x, y), inside the volume's box (values are all 1, which
    every drawn label's TF makes visible)."""
    origins, directions = camera.pixel_rays(SIZE, SIZE)
    origin, direction = origins[y, x], directions[y, x]
    t_far = float(ray_far(camera, direction[None, :])[0])
    t = np.arange(0.0, t_far, 1e-3)
    points = origin + t[:, None] * direction
    inside = np.all((points >= 0.0) & (points <= N - 1), axis=1)
    index = np.rint(points[inside]).astype(np.int64)
    found = volume.labels.values[index[:, 2], index[:, 1], index[:, 0]]
    drawn = np.array([label_tf.effective_tf(int(v)) is not None for v in range(256)])
    hits = np.flatnonzero(drawn[found])
    return int(found[hits[0]]) if hits.size else None


def _pixel_at(camera: Camera, world_x: float, world_y: float) -> tuple[int, int]:
    """The pixel whose ray passes nearest to (world_x, world_y) across the view (seen along -z)."""
    origins, _ = camera.pixel_rays(SIZE, SIZE)
    distance = np.hypot(origins[..., 0] - world_x, origins[..., 1] - world_y)
    y, x = np.unravel_index(np.argmin(distance), distance.shape)
    return int(x), int(y)


def test_the_centre_pixel_picks_the_ball_beside_it_the_slab_outside_nothing():
    volume, label_tf, camera = _scene()
    centre = _pixel_at(camera, C, C)
    beside = _pixel_at(camera, C + 8, C)
    outside = _pixel_at(camera, C + 14, C)
    hit = pick_label(volume, label_tf, camera, *centre, SIZE, SIZE)
    assert hit is not None and hit.label == 3
    assert hit.position[2] == pytest.approx(C + R + 0.5)  # enters the top voxel of the ball
    assert pick_label(volume, label_tf, camera, *beside, SIZE, SIZE).label == 1
    assert pick_label(volume, label_tf, camera, *outside, SIZE, SIZE) is None
    for pixel, expected in ((centre, 3), (beside, 1), (outside, None)):
        assert _brute_force(volume, label_tf, camera, *pixel) == expected


def test_picks_agree_with_the_brute_force_oracle_across_the_view():
    volume, label_tf, camera = _scene()
    for y in range(0, SIZE, 4):
        for x in range(0, SIZE, 4):
            hit = pick_label(volume, label_tf, camera, x, y, SIZE, SIZE)
            assert (hit.label if hit else None) == _brute_force(volume, label_tf, camera, x, y), (x, y)


def test_hidden_and_transparent_labels_are_passed_over():
    volume, label_tf, camera = _scene()
    centre, beside = _pixel_at(camera, C, C), _pixel_at(camera, C + 8, C)
    label_tf.set_style(3, LabelStyle(visible=False))  # the ball spans the slab on its axis: nothing left
    assert pick_label(volume, label_tf, camera, *centre, SIZE, SIZE) is None
    label_tf.set_style(3, LabelStyle())
    label_tf.set_style(1, LabelStyle(opacity=0.0))
    assert pick_label(volume, label_tf, camera, *beside, SIZE, SIZE) is None
    # a value the label's TF makes transparent: label 1 drawn, but with opacity 0 at value 1
    clear = TransferFunction1D(np.array([[0.0, 1, 1, 1]]), np.array([[0.0, 1.0], [1.0, 0.0]]))
    label_tf.set_style(1, LabelStyle(tf=clear))
    assert pick_label(volume, label_tf, camera, *beside, SIZE, SIZE) is None
    assert pick_label(volume, label_tf, camera, *centre, SIZE, SIZE).label == 3


def test_a_volume_without_labels_or_a_pixel_off_the_view_picks_nothing():
    volume, label_tf, camera = _scene()
    assert pick_label(replace(volume, labels=None), label_tf, camera, 32, 32, SIZE, SIZE) is None
    assert pick_label(volume, label_tf, camera, SIZE, 0, SIZE, SIZE) is None


def test_voxel_pieces_cut_the_ray_at_every_voxel_border():
    volume, _, camera = _scene()
    origin, direction = pixel_ray(camera, *_pixel_at(camera, C, C), SIZE, SIZE)
    cuts = voxel_pieces(volume, origin, direction, float(ray_far(camera, direction[None, :])[0]))
    depth = origin[2] - (origin + cuts[:, None] * direction)[:, 2]  # along -z: z falls from the top face
    np.testing.assert_allclose(depth - depth[0], [0.0, *np.arange(0.5, N - 1, 1.0), N - 1.0], atol=1e-9)
