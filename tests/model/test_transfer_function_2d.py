"""TransferFunction2D and TFWidget: widget formulas, combination, clamping, table, edits and
versions, validation, JSON round trips."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from volren.errors import VolrenError
from volren.model import TFWidget, TransferFunction1D, TransferFunction2D
from volren.model.transfer_function import MAX_OPACITY
from volren.model.transfer_function_2d import transfer_function_from_dict

RED, GREEN, BLUE = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)


def make_tf() -> TransferFunction2D:
    return TransferFunction2D(
        (0.0, 20.0),
        (0.0, 5.0),
        [
            TFWidget.gaussian((10.0, 2.0), (2.0, 0.5), RED, 0.8),
            TFWidget.box((5.0, 15.0), (1.0, 3.0), GREEN, 0.6),
            TFWidget.triangle(10.0, 4.0, 2.0, BLUE, 0.5),
        ],
        opacity_unit_distance=2.0,
    )


# ------------------------------------------------------------------------------ widget formulas
def test_gaussian_formula():
    w = TFWidget.gaussian((10.0, 2.0), (2.0, 0.5), RED, 0.8)
    # one standard deviation along each axis: exp(-1/2 - 1/2)
    got = w.opacity_at([10.0, 12.0, 8.0, 10.0, 14.0], [2.0, 2.5, 1.5, 3.0, 2.0])
    np.testing.assert_allclose(
        got, [0.8, 0.8 * math.exp(-1), 0.8 * math.exp(-1), 0.8 * math.exp(-2), 0.8 * math.exp(-2)], rtol=1e-15
    )


def test_box_is_constant_inside_closed_intervals_and_zero_outside():
    w = TFWidget.box((5.0, 15.0), (1.0, 3.0), GREEN, 0.6)
    s = [5.0, 15.0, 10.0, 10.0, 4.999, 15.001, 10.0, 10.0]
    g = [1.0, 3.0, 2.0, 1.0, 2.0, 2.0, 0.999, 3.001]
    np.testing.assert_array_equal(w.opacity_at(s, g), [0.6, 0.6, 0.6, 0.6, 0, 0, 0, 0])


def test_triangle_formula():
    # apex at (10, 0); half-width 4 at the top gradient 2, so h(g) = 2 g
    w = TFWidget.triangle(10.0, 4.0, 2.0, BLUE, 0.5)
    cases = [
        (10.0, 1.0, 0.5),  # centre line: the peak
        (11.0, 1.0, 0.25),  # halfway to the edge h(1) = 2
        (9.0, 1.0, 0.25),
        (12.0, 1.0, 0.0),  # on the edge
        (12.5, 1.0, 0.0),  # outside
        (13.0, 2.0, 0.125),  # at the top: h = 4, 1 - 3/4
        (10.0, 2.0001, 0.0),  # above gradient_max
        (10.0, 0.0, 0.5),  # the apex itself
        (10.001, 0.0, 0.0),  # next to the apex at g = 0: h = 0
        (10.0, -0.5, 0.0),  # negative gradient: nothing
        (10.2, 0.2, 0.25),  # h(0.2) = 0.4
    ]
    s, g, want = (np.array(c) for c in zip(*cases))
    np.testing.assert_allclose(w.opacity_at(s, g), want, rtol=1e-14, atol=1e-15)


def test_combination_rule():
    tf = TransferFunction2D(
        (0.0, 1.0),
        (0.0, 1.0),
        [TFWidget.box((0, 1), (0, 1), RED, 0.5), TFWidget.box((0.5, 1), (0, 1), BLUE, 0.25)],
    )
    rgb, alpha = tf.sample([0.25, 0.75], [0.5, 0.5])
    # one widget: itself; two: a = 1 - (1 - 0.5)(1 - 0.25), c = (0.5 red + 0.25 blue) / 0.75
    np.testing.assert_allclose(alpha, [0.5, 0.625], rtol=1e-15)
    np.testing.assert_allclose(rgb, [[1, 0, 0], [2 / 3, 0, 1 / 3]], rtol=1e-15)


def test_no_widget_and_nothing_present_give_zero():
    empty = TransferFunction2D((0, 1), (0, 1))
    rgb, alpha = empty.sample([0.5], [0.5])
    assert alpha[0] == 0 and np.all(rgb == 0)
    rgb, alpha = make_tf().sample([19.0], [4.9])  # outside every widget but the Gaussian's tail
    assert 0 < alpha[0] < 1e-11 and np.allclose(rgb[0], RED)  # colour is defined wherever a > 0


def test_sample_clamps_to_the_rectangle_and_broadcasts():
    tf = make_tf()
    s = np.array([[-5.0], [0.0], [25.0], [20.0]])
    g = np.array([[-1.0, 0.0, 7.0, 5.0]])
    rgb, alpha = tf.sample(s, g)
    assert rgb.shape == (4, 4, 3) and alpha.shape == (4, 4)
    np.testing.assert_array_equal(alpha[0], alpha[1])  # below lo: as at lo
    np.testing.assert_array_equal(alpha[2], alpha[3])  # above hi: as at hi
    np.testing.assert_array_equal(alpha[:, 0], alpha[:, 1])  # g < 0: as at 0
    np.testing.assert_array_equal(alpha[:, 2], alpha[:, 3])  # g > gmax: as at gmax
    _, inside = tf.sample(10.0, 2.0)
    want = 1 - (1 - 0.8) * (1 - 0.6) * (1 - 0.5 * (1 - 0 / 4))  # h(2) = 4, on the centre line
    assert inside == pytest.approx(want, rel=1e-15)


def test_nonfinite_inputs_are_transparent():
    rgb, alpha = make_tf().sample([np.nan, 10.0, np.inf, 10.0], [2.0, np.nan, 2.0, 2.0])
    assert np.all(alpha[:3] == 0) and np.all(rgb[:3] == 0) and alpha[3] > 0


def test_extinction_follows_the_unit_distance_convention():
    tf = make_tf()
    _, alpha = tf.sample([10.0], [2.0])
    tau = tf.extinction([10.0], [2.0])
    assert 1 - np.exp(-tau[0] * 2.0) == pytest.approx(alpha[0], rel=1e-12)
    full = TransferFunction2D((0, 1), (0, 1), [TFWidget.box((0, 1), (0, 1), RED, 1.0)], 0.5)
    assert full.extinction(0.5, 0.5) == pytest.approx(-math.log(1 - MAX_OPACITY) / 0.5)


def test_table_layout_matches_sample():
    tf = make_tf()
    table = tf.table(11, 6)
    assert table.dtype == np.float32 and table.shape == (6, 11, 4)
    s = np.linspace(0, 20, 11)
    g = np.linspace(0, 5, 6)
    rgb, alpha = tf.sample(s[None, :], g[:, None])
    np.testing.assert_allclose(table[..., :3], rgb, atol=1e-7)
    np.testing.assert_allclose(table[..., 3], alpha, atol=1e-7)
    assert table[2, 5, 3] == pytest.approx(tf.sample(10.0, 2.0)[1], abs=1e-7)  # row j = gradient
    with pytest.raises(VolrenError, match="n_values >= 2"):
        tf.table(1, 4)


@settings(max_examples=50, deadline=None)
@given(
    st.lists(st.floats(-30, 30), min_size=1, max_size=8),
    st.lists(st.floats(-2, 8), min_size=1, max_size=8),
)
def test_sample_stays_in_range(values, gradients):
    rgb, alpha = make_tf().sample(np.array(values)[:, None], np.array(gradients)[None, :])
    assert np.all((alpha >= 0) & (alpha <= 1)) and np.all((rgb >= 0) & (rgb <= 1))


# ---------------------------------------------------------------------------- edits, versions
def test_every_edit_changes_the_version_and_notifies():
    tf = make_tf()
    seen = []
    disconnect = tf.on_change(lambda t: seen.append(t.version))
    versions = [tf.version]
    index = tf.add_widget(TFWidget.gaussian((5.0, 1.0), (1.0, 1.0), GREEN, 0.3))
    assert index == 3
    tf.replace_widget(0, TFWidget.box((0, 1), (0, 1), RED, 0.1))
    removed = tf.remove_widget(-1)
    assert removed.type == "gaussian" and len(tf.widgets) == 3
    tf.set_widgets(tf.widgets[:1])
    tf.set_value_range(-1.0, 30.0)
    tf.set_gradient_range(9.0)
    tf.set_opacity_unit_distance(3.0)
    versions += seen
    assert len(seen) == 7 and len(set(versions)) == 8 and versions == sorted(versions)
    assert (
        tf.value_range == (-1.0, 30.0) and tf.gradient_range == (0.0, 9.0) and tf.opacity_unit_distance == 3.0
    )
    disconnect()
    tf.set_opacity_unit_distance(4.0)
    assert len(seen) == 7


def test_versions_come_from_the_counter_shared_with_1d():
    versions = []
    for _ in range(3):
        versions.append(TransferFunction1D.ramp(0, 1).version)
        versions.append(make_tf().version)
    tf1, tf2 = TransferFunction1D.ramp(0, 1), make_tf()
    tf1.set_opacity_unit_distance(2.0)
    versions.append(tf1.version)
    tf2.set_opacity_unit_distance(2.0)
    versions.append(tf2.version)
    assert versions == sorted(versions) and len(set(versions)) == len(versions)


def test_failed_edits_change_nothing():
    tf = make_tf()
    version, widgets = tf.version, tf.widgets
    for edit in (
        lambda: tf.replace_widget(7, widgets[0]),
        lambda: tf.remove_widget(3),
        lambda: tf.add_widget("box"),
        lambda: tf.set_value_range(2, 1),
        lambda: tf.set_gradient_range(0),
        lambda: tf.set_opacity_unit_distance(-1),
    ):
        with pytest.raises(VolrenError):
            edit()
    assert tf.version == version and tf.widgets == widgets


def test_dims_copy_and_equality():
    assert TransferFunction1D.dims == 1 and TransferFunction2D.dims == 2 and make_tf().dims == 2
    tf = make_tf()
    tf.extra["note"] = "kept"
    twin = tf.copy()
    assert twin == tf and twin is not tf and twin.extra == {"note": "kept"} and twin.version != tf.version
    twin.remove_widget(0)
    assert twin != tf and len(tf.widgets) == 3
    assert tf != TransferFunction1D.ramp(0, 1)
    assert "TransferFunction2D(gaussian, box, triangle" in repr(tf)


def test_widgets_are_immutable_and_replace_validates():
    from dataclasses import FrozenInstanceError, replace

    w = TFWidget.box((0, 1), (0, 2), RED, 0.5)
    with pytest.raises(FrozenInstanceError):
        w.opacity = 1.0  # type: ignore[misc]
    assert replace(w, opacity=0.25).opacity == 0.25
    with pytest.raises(VolrenError, match="box widget: opacity must lie in"):
        replace(w, opacity=2.0)
    assert w == TFWidget("box", [1, 0, 0], 0.5, value_range=[0, 1], gradient_range=[0, 2])
    assert hash(w) == hash(TFWidget.box((0.0, 1.0), (0.0, 2.0), RED, 0.5))


# --------------------------------------------------------------------------------- validation
@pytest.mark.parametrize(
    "build, fragment",
    [
        (lambda: TFWidget("circle", RED, 0.5), "unknown widget type 'circle'"),
        (
            lambda: TFWidget.gaussian((0, 1), (0, 1), RED, 0.5),
            "gaussian widget: width (standard deviations) must be positive",
        ),
        (lambda: TFWidget.gaussian((0, -1), (1, 1), RED, 0.5), "center gradient must be >= 0"),
        (lambda: TFWidget.gaussian((0, 1, 2), (1, 1), RED, 0.5), "center must be a list of 2 numbers"),
        (lambda: TFWidget.gaussian((0, math.nan), (1, 1), RED, 0.5), "center must be finite"),
        (
            lambda: TFWidget.box((2, 1), (0, 1), RED, 0.5),
            "box widget: value_range must be [lo, hi] with lo < hi",
        ),
        (lambda: TFWidget.box((0, 1), (-1, 1), RED, 0.5), "gradient_range must not start below 0"),
        (lambda: TFWidget.triangle(0, 0, 1, RED, 0.5), "triangle widget: half_width must be positive"),
        (lambda: TFWidget.triangle(0, 1, -1, RED, 0.5), "gradient_max must be positive"),
        (lambda: TFWidget.triangle("a", 1, 1, RED, 0.5), "value must be a number"),
        (lambda: TFWidget.box((0, 1), (0, 1), (1, 0, 2), 0.5), "color values must lie in [0, 1]"),
        (lambda: TFWidget.box((0, 1), (0, 1), (1, 0), 0.5), "color must be a list of 3 numbers"),
        (lambda: TFWidget.box((0, 1), (0, 1), RED, 1.5), "opacity must lie in [0, 1]"),
        (lambda: TFWidget.box((0, 1), (0, 1), RED, True), "opacity must be a number"),
        (lambda: TFWidget("box", RED, 0.5, value_range=(0, 1)), "box widget: missing 'gradient_range'"),
        (
            lambda: TFWidget("box", RED, 0.5, value_range=(0, 1), gradient_range=(0, 1), center=(0, 0)),
            "box widget: 'center' does not apply",
        ),
        (lambda: TransferFunction2D((1, 1), (0, 1)), "value_range must be [lo, hi] with lo < hi"),
        (lambda: TransferFunction2D((0, 1), (1, 2)), "gradient_range must be [0, gmax] with gmax > 0"),
        (lambda: TransferFunction2D((0, 1), (0, 0)), "gradient_range must be [0, gmax] with gmax > 0"),
        (lambda: TransferFunction2D((0, 1), (0, 1), [{"type": "box"}]), "widget 0 must be a TFWidget"),
        (lambda: TransferFunction2D((0, 1), (0, 1), opacity_unit_distance=0), "must be positive"),
    ],
)
def test_bad_geometry_is_one_line_saying_what(build, fragment):
    with pytest.raises(VolrenError) as info:
        build()
    message = str(info.value)
    assert fragment in message and "\n" not in message, message


# ------------------------------------------------------------------------------------- JSON
def test_dict_round_trip_keeps_unknown_keys():
    tf = make_tf()
    data = tf.to_dict()
    assert data["version"] == 1 and data["kind"] == "2d" and data["gradient_range"] == [0.0, 5.0]
    assert data["widgets"][0] == {
        "type": "gaussian", "center": [10.0, 2.0], "width": [2.0, 0.5], "color": [1.0, 0.0, 0.0], "opacity": 0.8,
    }  # fmt: skip
    assert data["widgets"][1]["value_range"] == [5.0, 15.0] and data["widgets"][1]["gradient_range"] == [
        1.0,
        3.0,
    ]
    assert {k: data["widgets"][2][k] for k in ("value", "half_width", "gradient_max")} == {
        "value": 10.0, "half_width": 4.0, "gradient_max": 2.0,
    }  # fmt: skip
    data["painted_by"] = {"tool": "editor"}
    data["widgets"][1]["label"] = "bone"
    data["widgets"][2]["center"] = [1, 2]  # another type's key: kept, not used
    back = TransferFunction2D.from_dict(data)
    assert back == tf and back.extra == {"painted_by": {"tool": "editor"}}
    assert back.widgets[1].extra == {"label": "bone"}
    assert back.to_dict() == data
    assert transfer_function_from_dict(data) == tf
    assert isinstance(
        transfer_function_from_dict(TransferFunction1D.ramp(0, 1).to_dict()), TransferFunction1D
    )


@pytest.mark.parametrize(
    "change, fragment",
    [
        ({"version": 2}, "format version 2 is newer than this volren reads"),
        ({"kind": "3d"}, "unknown transfer-function kind '3d'"),
        ({"widgets": None}, "'widgets' must be a list"),
        ({"widgets": [[1, 2]]}, "widget 0: must be a JSON object"),
        ({"widgets": [{"color": [1, 1, 1], "opacity": 1}]}, "widget 0: missing 'type'"),
        ({"widgets": [{"type": "blob"}]}, "widget 0: unknown type 'blob'"),
        (
            {"widgets": [{"type": "gaussian", "center": [0, 0], "color": [1, 1, 1], "opacity": 1}]},
            "missing 'width'",
        ),
        ({"value_range": "all"}, "value_range must be a list of 2 numbers"),
    ],
)
def test_bad_dicts(change, fragment):
    data = {**make_tf().to_dict(), **change}
    with pytest.raises(VolrenError) as info:
        transfer_function_from_dict(data)
    assert fragment in str(info.value), str(info.value)


# ------------------------------------------------------------------------------- 1d widgets
STEPPED = TransferFunction1D(
    [[0.0, 1.0, 0.0, 0.0], [8.0, 0.0, 1.0, 0.0], [8.0, 0.0, 0.0, 1.0], [16.0, 1.0, 1.0, 1.0]],
    [[2.0, 0.0], [6.0, 0.7], [12.0, 0.2], [12.0, 0.9], [14.0, 0.0]],
)
ONE_D = TFWidget("1d", (0.5, 1.0, 0.8), 0.6, gradient_range=(1.0, 3.0),
                 color_points=STEPPED.color_points, opacity_points=STEPPED.opacity_points)  # fmt: skip


def test_a_1d_widget_is_its_1d_tf_scaled_and_tinted_inside_its_band():
    s = np.linspace(-3.0, 19.0, 221)  # steps, kinks and both constant ends
    rgb, alpha = STEPPED.sample(s)
    for g, inside in ((1.0, True), (2.0, True), (3.0, True), (0.999, False), (3.001, False)):
        np.testing.assert_array_equal(ONE_D.opacity_at(s, g), 0.6 * alpha if inside else 0.0)
    np.testing.assert_array_equal(ONE_D.color_at(s), rgb * (0.5, 1.0, 0.8))
    tf = TransferFunction2D((-3.0, 19.0), (0.0, 5.0), [ONE_D])
    got_rgb, got_alpha = tf.sample(s, 2.0)
    np.testing.assert_allclose(got_alpha, 0.6 * alpha, atol=1e-15, rtol=0)
    # its colour also where it is transparent (as a 1D TF has one), none outside its band
    np.testing.assert_allclose(got_rgb, rgb * (0.5, 1.0, 0.8), atol=1e-15, rtol=0)
    assert np.all(tf.sample(s, 4.0)[0] == 0.0)


def test_a_1d_widget_combines_with_the_others_as_widgets_do():
    box = TFWidget.box((4.0, 10.0), (0.0, 5.0), BLUE, 0.5)
    tf = TransferFunction2D((0.0, 16.0), (0.0, 5.0), [ONE_D, box])
    s = np.array([1.0, 5.0, 7.0, 9.0, 13.0])
    a1, a2 = ONE_D.opacity_at(s, 2.0), box.opacity_at(s, 2.0)
    c1 = ONE_D.color_at(s)
    rgb, alpha = tf.sample(s, 2.0)
    np.testing.assert_allclose(alpha, 1 - (1 - a1) * (1 - a2), atol=1e-15)
    weight = np.where(a1 + a2 > 0, a1 + a2, 1.0)[:, None]
    expected = np.where((a1 + a2 > 0)[:, None], (a1[:, None] * c1 + a2[:, None] * BLUE) / weight, c1)
    np.testing.assert_allclose(rgb, expected, atol=1e-15)


def test_from_1d_draws_the_1d_tf_at_every_gradient():
    tf = TransferFunction2D((-3.0, 19.0), (0.0, 5.0), [TFWidget.from_1d(STEPPED, (0.0, 5.0))], 2.0)
    lut = STEPPED.to_lut(111, (-3.0, 19.0))
    table = tf.table(111, 6)
    assert np.abs(table - lut[None]).max() <= 1e-7


def test_a_1d_widget_round_trips_through_json_and_validates():
    tf = TransferFunction2D((0.0, 16.0), (0.0, 5.0), [ONE_D, TFWidget.box((1, 2), (0, 1), RED, 0.5)])
    data = tf.to_dict()
    assert data["widgets"][0] == {
        "type": "1d", "color_points": STEPPED.color_points.tolist(), "opacity_points": STEPPED.opacity_points.tolist(),
        "gradient_range": [1.0, 3.0], "color": [0.5, 1.0, 0.8], "opacity": 0.6,
    }  # fmt: skip
    assert transfer_function_from_dict(data) == tf and transfer_function_from_dict(data).to_dict() == data
    back = TFWidget.from_dict(data["widgets"][0])
    assert back == ONE_D and hash(back) == hash(ONE_D)


@pytest.mark.parametrize(
    "change, fragment",
    [
        ({"opacity_points": [[0, "a"]]}, "widget 0: 1d widget: opacity points must be numbers"),
        ({"color_points": []}, "widget 0: 1d widget: colour points must be a non-empty list of 4-tuples"),
        ({"opacity_points": [[0, 1.5]]}, "widget 0: 1d widget: opacity values must lie in [0, 1]"),
        ({"gradient_range": [-1, 2]}, "widget 0: 1d widget: gradient_range must not start below 0"),
        ({"opacity_points": None}, "widget 0: 1d widget: missing 'opacity_points'"),
        ({"value_range": [0, 1]}, None),  # another type's key: kept, not used
    ],
)
def test_bad_1d_widgets_are_one_line_saying_what(change, fragment):
    data = TransferFunction2D((0.0, 16.0), (0.0, 5.0), [ONE_D]).to_dict()
    data["widgets"][0].update(change)
    data["widgets"][0] = {k: v for k, v in data["widgets"][0].items() if v is not None}
    if fragment is None:
        assert transfer_function_from_dict(data).widgets[0].extra == change
        return
    with pytest.raises(VolrenError) as info:
        transfer_function_from_dict(data)
    assert fragment in str(info.value) and "\n" not in str(info.value), str(info.value)
    with pytest.raises(VolrenError, match="1d widget: 'center' does not apply"):
        TFWidget("1d", RED, 1.0, center=(0, 0), gradient_range=(0, 1), color_points=[[0, 1, 1, 1]],
                 opacity_points=[[0, 1]])  # fmt: skip
