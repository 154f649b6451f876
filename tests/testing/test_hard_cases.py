"""The hard scenes (`volren.testing.hard_cases`) and the fidelity count (`volren.testing.metrics`)."""

from __future__ import annotations

import numpy as np
import pytest

from volren.bench.datasets import HARD_GROUP, select
from volren.testing.hard_cases import CASES, FEATURE_SIZES, tube_field
from volren.testing.metrics import OFF_THRESHOLD, image_error, off_pixels


def test_a_pixel_is_off_when_any_channel_differs_by_more_than_the_threshold():
    reference = np.zeros((4, 5, 4), np.float32)
    image = reference.copy()
    image[0, 0, 3] = OFF_THRESHOLD + 0.01  # alpha only
    image[1, 2, :] = -0.5  # every channel, one pixel
    image[3, 4, 0] = OFF_THRESHOLD - 0.01  # within the threshold
    assert off_pixels(image - reference) == 2
    err = image_error(image, reference)
    assert err.off == 2 and "2 px off" in str(err)


def test_tubes_are_as_thin_as_said_and_antialiased_over_one_voxel():
    field = tube_field((48, 48, 48), seed=11)
    assert field.max() == 1.0 and field.min() == 0.0
    # the thinnest tube (radius 0.5) still reaches full value on its axis, and values between 0
    # and 1 exist (the one-voxel edge): nothing is a bare binary mask
    partial = (field > 0.0) & (field < 1.0)
    assert partial.sum() > 0.5 * (field == 1.0).sum()
    assert FEATURE_SIZES[0] == 0.5


@pytest.mark.parametrize("name", sorted(CASES))
def test_every_hard_scene_builds_with_its_tf_showing_something(name):
    case = CASES[name]
    volume = case.build()
    assert volume.kind == case.kind
    tf = case.tf()
    lo, hi = volume.value_range
    _, alpha = tf.sample(np.linspace(lo, hi, 256))
    assert alpha.max() > 0.2  # the features are visible
    # the same volume every time: the scenes are seeded
    again = case.build()
    assert np.array_equal(np.asarray(volume.values), np.asarray(again.values))


def test_the_bench_names_every_hard_scene_by_one_group_name():
    chosen = select([HARD_GROUP, "marschner_lobb"], None)
    assert [d.name for d in chosen] == [*sorted(CASES, key=list(CASES).index), "marschner_lobb"]
    hard = chosen[0]
    assert hard.styles == ("hard",)
    volume = hard.load()
    assert hard.camera(volume.bounds).position != hard.camera(volume.bounds, turn=2.0).position
    # the default set stays the shared scenes and samples (the hard ones are asked for by name)
    assert not any(d.name in CASES for d in select(None, None))
