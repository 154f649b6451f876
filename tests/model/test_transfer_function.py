"""TransferFunction1D: sampling, extinction, LUT, edits and versions, JSON round trips."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from volren.errors import VolrenError
from volren.model.transfer_function import MAX_OPACITY, TransferFunction1D


def make_tf() -> TransferFunction1D:
    return TransferFunction1D(
        [[0, 0, 0, 1], [100, 1, 0, 0], [200, 0, 1, 0]], [[50, 0.0], [150, 0.8]], opacity_unit_distance=2.0
    )


def test_sample_is_piecewise_linear_and_constant_beyond_the_ends():
    tf = make_tf()
    rgb, alpha = tf.sample([-10, 0, 50, 100, 150, 250])
    np.testing.assert_allclose(rgb[:, 0], [0, 0, 0.5, 1, 0.5, 0])
    np.testing.assert_allclose(rgb[:, 2], [1, 1, 0.5, 0, 0, 0])
    np.testing.assert_allclose(alpha, [0, 0, 0, 0.4, 0.8, 0.8])


def test_nonfinite_values_are_transparent():
    rgb, alpha = make_tf().sample([np.nan, np.inf, -np.inf, 150])
    assert np.all(alpha[:3] == 0) and np.all(rgb[:3] == 0)
    assert alpha[3] == pytest.approx(0.8)


def test_extinction_follows_the_unit_distance_convention():
    tf = make_tf()
    # A slab one unit distance thick has the TF's opacity: 1 - exp(-tau * d_u) = a.
    tau = tf.extinction([150.0])
    assert 1 - np.exp(-tau[0] * 2.0) == pytest.approx(0.8, rel=1e-12)
    full = TransferFunction1D.constant(1.0, opacity_unit_distance=1.0)
    assert full.extinction([0.0])[0] == pytest.approx(-np.log(1 - MAX_OPACITY))


def test_lut_matches_sample():
    tf = make_tf()
    lut = tf.to_lut(11, (0, 200))
    rgb, alpha = tf.sample(np.linspace(0, 200, 11))
    np.testing.assert_allclose(lut[:, :3], rgb, atol=1e-7)
    np.testing.assert_allclose(lut[:, 3], alpha, atol=1e-7)
    assert lut.dtype == np.float32 and lut.shape == (11, 4)


def test_every_edit_changes_the_version_and_notifies():
    tf = make_tf()
    seen = []
    disconnect = tf.on_change(lambda t: seen.append(t.version))
    versions = {tf.version}
    tf.set_opacity_points([[0, 0], [1, 1]])
    tf.set_color_points([[0, 1, 1, 1]])
    tf.set_opacity_unit_distance(3.0)
    tf.rescale(10, 20)
    versions.update(seen)
    assert len(versions) == 5 and seen == sorted(seen)
    disconnect()
    tf.set_opacity_unit_distance(1.0)
    assert len(seen) == 4
    # Versions are unique across instances, so caches can key on them alone.
    assert make_tf().version not in versions | {tf.version}


def test_rescale_maps_points_onto_the_new_range():
    tf = make_tf()
    tf.rescale(0.0, 1.0)
    assert tf.value_range == (0.0, 1.0)
    assert tf.opacity_points[:, 0].tolist() == [0.25, 0.75]


def test_json_round_trip_keeps_unknown_keys():
    tf = make_tf()
    data = tf.to_dict()
    data["name"] = "mine"
    data["future_field"] = {"x": 1}
    again = TransferFunction1D.from_dict(data)
    assert again == tf
    assert again.to_dict()["future_field"] == {"x": 1} and again.to_dict()["name"] == "mine"


@pytest.mark.parametrize(
    "data, message",
    [
        ({"version": 2, "color": [[0, 0, 0, 0]], "opacity": [[0, 0]]}, "newer"),
        ({"version": 1, "kind": "3d", "color": [[0, 0, 0, 0]], "opacity": [[0, 0]]}, "kind"),
        ({"version": 1, "opacity": [[0, 0]]}, "missing 'color'"),
        ({"version": 1, "color": [[0, 0, 0]], "opacity": [[0, 0]]}, "4-tuples"),
        ({"version": 1, "color": [[0, 0, 0, 2]], "opacity": [[0, 0]]}, r"\[0, 1\]"),
        ({"version": 1, "color": [[0, 0, 0, 0]], "opacity": [[float("nan"), 0]]}, "NaN"),
        ({"version": 1, "color": [[0, 0, 0, 0]], "opacity": []}, "non-empty"),
        ({"version": 1, "color": [["a", 0, 0, 0]], "opacity": [[0, 0]]}, "numbers"),
        ({"version": "1", "color": [[0, 0, 0, 0]], "opacity": [[0, 0]]}, "integer"),
        (
            {"version": 1, "color": [[0, 0, 0, 0]], "opacity": [[0, 0]], "opacity_unit_distance": 0},
            "positive",
        ),
        ([1, 2], "JSON object"),
    ],
)
def test_malformed_json_gives_a_clear_error(data, message):
    with pytest.raises(VolrenError, match=message):
        TransferFunction1D.from_dict(data)


@settings(max_examples=60, deadline=None)
@given(
    xs=st.lists(st.floats(-1e6, 1e6), min_size=1, max_size=8),
    alphas=st.lists(st.floats(0, 1), min_size=8, max_size=8),
    queries=st.lists(st.floats(-2e6, 2e6), min_size=1, max_size=20),
)
def test_sampling_stays_in_range(xs, alphas, queries):
    tf = TransferFunction1D([[x, 0.5, 0.5, 0.5] for x in xs], [[x, a] for x, a in zip(xs, alphas)])
    rgb, alpha = tf.sample(queries)
    assert np.all((alpha >= 0) & (alpha <= 1)) and np.all((rgb >= 0) & (rgb <= 1))
    assert np.all(np.isfinite(tf.extinction(queries)))


def test_absurdly_small_unit_distance_is_refused():
    """13.8 / d_u (an opaque value's extinction) must stay finite in every table and integrator."""
    with pytest.raises(VolrenError, match="absurdly small"):
        TransferFunction1D.constant(1.0, opacity_unit_distance=1e-308)
    assert TransferFunction1D.constant(1.0, opacity_unit_distance=1e-30).opacity_unit_distance == 1e-30
