"""Cropping to an axis-aligned box: the sub-grid or the whole tetrahedra inside, exactly."""

from __future__ import annotations

import numpy as np
import pytest

from volren.errors import VolrenError
from volren.model.crop import check_box, crop_volume
from volren.model.volume import TetVolume, UniformVolume


@pytest.fixture
def grid() -> UniformVolume:
    values = np.arange(6 * 5 * 4, dtype=np.float32).reshape(6, 5, 4)  # (z, y, x): 4 x 5 x 6 samples
    return UniformVolume(values, spacing=(0.5, 1.0, 2.0), origin=(1.0, 0.0, -2.0))


def test_uniform_crop_keeps_the_samples_inside_the_box(grid):
    # x samples at 1, 1.5, 2, 2.5; y at 0..4; z at -2, 0, ..., 8
    # the box snaps outwards to whole samples: x [1.6, 2.0] -> samples 1.5, 2; y [0.5, 3] -> 0..3;
    # z [-2, 1] -> -2, 0, 2
    cropped = crop_volume(grid, (1.6, 2.0, 0.5, 3.0, -2.0, 1.0))
    assert cropped.origin == (1.5, 0.0, -2.0)
    np.testing.assert_array_equal(cropped.values, grid.values[0:3, 0:4, 1:3])
    assert cropped.spacing == grid.spacing


def test_uniform_crop_keeps_two_samples_for_a_thin_box(grid):
    cropped = crop_volume(grid, (1.6, 1.6, 0.0, 4.0, -2.0, 8.0))
    assert cropped.dimensions[0] == 2 and cropped.origin[0] == 1.5
    cropped = crop_volume(grid, (9.0, 9.5, 0.0, 4.0, -2.0, 8.0))  # beyond the data: the last two samples
    assert cropped.dimensions[0] == 2 and cropped.origin[0] == 2.0


def test_a_box_covering_the_volume_returns_it_unchanged(grid):
    assert crop_volume(grid, (-10, 10, -10, 10, -10, 10)) is grid


def test_mesh_crop_keeps_whole_tetrahedra_inside():
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [2, 0, 0], [2, 1, 0], [2, 0, 1]], float)
    tets = np.array([[0, 1, 2, 3], [1, 4, 5, 6]])
    mesh = TetVolume(points, tets, np.arange(7, dtype=np.float64))
    cropped = crop_volume(mesh, (-0.5, 1.5, -0.5, 1.5, -0.5, 1.5))
    assert len(cropped.tets) == 1 and len(cropped.points) == 4
    np.testing.assert_array_equal(cropped.points[cropped.tets[0]], points[tets[0]])
    np.testing.assert_array_equal(cropped.values[cropped.tets[0]], [0, 1, 2, 3])
    with pytest.raises(VolrenError, match="no tetrahedron"):
        crop_volume(mesh, (0.2, 0.3, 0.2, 0.3, 0.2, 0.3))


@pytest.mark.parametrize(
    "box", [(0, 1, 0, 1, 0), (0, 1, 0, 1, 0, float("nan")), (1, 0, 0, 1, 0, 1), "abcdef"]
)
def test_malformed_boxes_are_one_line_errors(box):
    with pytest.raises(VolrenError) as info:
        check_box(box)
    assert "\n" not in str(info.value) and "crop box" in str(info.value)


def test_a_crop_cuts_the_labels_and_the_channels_with_the_values():
    from volren.model.channels import ChannelSet
    from volren.model.labels import LabelMap

    values = np.arange(4 * 5 * 6, dtype=np.float32).reshape(4, 5, 6)
    labels = (values.astype(np.int64) % 7).astype(np.uint8)
    volume = UniformVolume(values, labels=LabelMap(labels, names={3: "three"}),
                           channels=ChannelSet(np.stack([values, -values])))  # fmt: skip
    cropped = crop_volume(volume, (1.0, 3.0, 0.0, 2.0, 1.0, 3.0))
    assert isinstance(cropped, UniformVolume)
    np.testing.assert_array_equal(cropped.labels.values, labels[1:4, 0:3, 1:4])
    assert cropped.labels.names == {3: "three"}
    np.testing.assert_array_equal(cropped.channels.values[1], -values[1:4, 0:3, 1:4])
    np.testing.assert_array_equal(cropped.values, values[1:4, 0:3, 1:4])
