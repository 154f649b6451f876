"""Movie timelines: the orbit, keyframe interpolation of cameras and TFs, and scene-file errors."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from volren.errors import VolrenError
from volren.model.animation import Animation, CameraKey, TFKey, blend_views
from volren.model.camera import Camera
from volren.model.scene import OrbitView
from volren.model.tf_blend import blend_transfer_functions
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TFWidget, TransferFunction2D

BOUNDS = (0.0, 2.0, 0.0, 1.0, 0.0, 3.0)


def test_a_full_orbit_loops_and_frame_i_is_the_render_azimuth():
    start = OrbitView(azimuth=10, elevation=20, zoom=1.5)
    movie = Animation(frames=8, orbit_degrees=360)
    assert movie.loops
    assert [movie.view(i, start).azimuth for i in range(8)] == [10 + 45 * i for i in range(8)]
    assert movie.camera(3, start, BOUNDS, 4 / 3) == OrbitView(145, 20, 1.5).camera(BOUNDS, 4 / 3)


def test_a_part_orbit_ends_on_its_last_angle():
    movie = Animation(frames=5, orbit_degrees=90)
    assert not movie.loops
    assert [movie.orbit_angle(i) for i in range(5)] == [0, 22.5, 45, 67.5, 90]
    assert Animation(frames=1, orbit_degrees=90).orbit_angle(0) == 0


def test_an_explicit_camera_orbits_about_its_view_up_at_constant_distance():
    start = Camera.orbit(BOUNDS, 0, 30)
    movie = Animation(frames=4)
    cameras = [movie.camera(i, start, BOUNDS, 1.0) for i in range(4)]
    assert np.allclose([c.distance for c in cameras], start.distance)
    offset, up = (
        np.subtract(start.position, start.focal_point),
        np.asarray(start.view_up) / np.linalg.norm(start.view_up),
    )
    half_turn = 2 * (offset @ up) * up - offset  # 180 degrees about the view-up axis
    assert np.allclose(np.subtract(cameras[2].position, start.focal_point), half_turn)


def test_orbit_keyframes_interpolate_linearly_and_hold_outside():
    keys = (CameraKey(0.25, OrbitView(0, 0, 1)), CameraKey(0.75, OrbitView(180, 40, 4)))
    movie = Animation(frames=5, camera_keys=keys)
    views = [movie.view(i, OrbitView()) for i in range(5)]
    assert views[0] == views[1] == OrbitView(0, 0, 1)
    assert views[3] == views[4] == OrbitView(180, 40, 4)
    assert views[2].azimuth == 90 and views[2].elevation == 20 and math.isclose(views[2].zoom, 2.0)


def test_camera_keyframes_slerp_direction_and_lerp_distance():
    a = Camera(position=(0, 0, 2), focal_point=(0, 0, 0), view_up=(0, 1, 0))
    b = Camera(position=(4, 0, 0), focal_point=(0, 0, 0), view_up=(0, 1, 0))
    mid = blend_views(a, b, 0.5)
    assert math.isclose(mid.distance, 3.0)
    assert np.allclose(-mid.direction, np.array([1, 0, 1]) / math.sqrt(2))
    assert np.allclose(mid.view_up, (0, 1, 0))


def test_mixed_or_inconsistent_keyframes_are_refused():
    with pytest.raises(VolrenError, match="all be orbit views"):
        Animation(camera_keys=(CameraKey(0, OrbitView()), CameraKey(1, Camera())))
    with pytest.raises(VolrenError, match="all be parallel"):
        Animation(camera_keys=(CameraKey(0, OrbitView()), CameraKey(1, OrbitView(parallel=True))))
    with pytest.raises(VolrenError, match="all be 1D or all 2D"):
        Animation(tf_keys=(TFKey(0, TransferFunction1D.ramp(0, 1)), TFKey(1, _tf2d(0.5))))


def _tf1d(points: list[list[float]], colors: list[list[float]], unit: float = 1.0) -> TransferFunction1D:
    return TransferFunction1D(colors, points, unit)


curve = st.lists(st.tuples(st.integers(-4, 4), st.floats(0, 1)), min_size=1, max_size=5).map(
    lambda pts: sorted([[float(x), a] for x, a in pts], key=lambda p: p[0])
)


@settings(max_examples=60, deadline=None)
@given(curve, curve, st.floats(0.01, 0.99))
def test_blended_1d_tf_is_the_weighted_sum_everywhere_steps_included(a_pts, b_pts, weight):
    """The oracle: (1 - w) a(x) + w b(x) at every x, including just left and right of each corner
    (where a repeated x makes a step)."""
    a = _tf1d(a_pts, [[0, 1, 0, 0], [1, 0, 0, 1]], 1.0)
    b = _tf1d(b_pts, [[-1, 0, 1, 0]], 3.0)
    mix = blend_transfer_functions(a, b, weight)
    corners = np.union1d(a.opacity_points[:, 0], b.opacity_points[:, 0])
    xs = np.concatenate([np.linspace(-6, 6, 97), corners - 1e-9, corners + 1e-9])
    for x in xs:
        expected = (1 - weight) * a.sample(x)[1] + weight * b.sample(x)[1]
        assert math.isclose(float(mix.sample(x)[1]), float(expected), abs_tol=1e-7), x
    expected_rgb = (1 - weight) * a.sample(xs)[0] + weight * b.sample(xs)[0]
    assert np.allclose(mix.sample(xs)[0], expected_rgb, atol=1e-7)
    assert math.isclose(mix.opacity_unit_distance, (1 - weight) * 1.0 + weight * 3.0)


def _tf2d(opacity: float, center: float = 0.5) -> TransferFunction2D:
    return TransferFunction2D(
        (0, 1),
        (0, 2),
        [
            TFWidget.gaussian((center, 0.5), (0.1, 0.2), (1, 0, 0), opacity),
            TFWidget.box((0.2, 0.4), (0, 1), (0, 1, 0), opacity / 2),
        ],
    )


def test_blended_2d_tf_moves_each_widget_and_refuses_other_widget_sets():
    mix = blend_transfer_functions(_tf2d(0.2, 0.3), _tf2d(0.6, 0.7), 0.25)
    assert math.isclose(mix.widgets[0].opacity, 0.3) and math.isclose(mix.widgets[0].center[0], 0.4)
    assert math.isclose(mix.widgets[1].opacity, 0.15)
    other = TransferFunction2D((0, 1), (0, 2), [TFWidget.triangle(0.5, 0.1, 1, (1, 1, 1), 1)])
    with pytest.raises(VolrenError, match="1 widgets"):
        blend_transfer_functions(_tf2d(0.2), other, 0.5)


def test_tf_keyframes_give_the_keyframe_itself_where_it_holds():
    a, b = TransferFunction1D.ramp(0, 1, 0.2), TransferFunction1D.ramp(0, 1, 0.8)
    movie = Animation(frames=5, tf_keys=(TFKey(0.5, a), TFKey(1.0, b)))
    start = TransferFunction1D.ramp(0, 1)
    assert movie.transfer_function(0, start) is a and movie.transfer_function(2, start) is a
    assert movie.transfer_function(4, start) is b
    assert math.isclose(float(movie.transfer_function(3, start).sample(1.0)[1]), 0.5)
    assert Animation(frames=3).transfer_function(1, start) is start


def test_from_dict_reads_a_scene_movie():
    tf = TransferFunction1D.ramp(0, 1, 0.5).to_dict()
    movie = Animation.from_dict(
        {
            "frames": 10,
            "fps": 12,
            "keyframes": [
                {"time": 1, "camera": {"azimuth": 90}},
                {"time": 0, "camera": {"azimuth": 0}, "transfer_function": tf},
            ],
        }
    )
    assert movie.frames == 10 and movie.fps == 12 and [k.time for k in movie.camera_keys] == [0, 1]
    assert len(movie.tf_keys) == 1 and movie.seconds == 10 / 12


@pytest.mark.parametrize(
    "data, message",
    [
        ([], "must be a JSON object"),
        ({"frames": 0}, "movie: frames must be a whole number"),
        ({"frames": 2.5}, "movie: frames must be a whole number"),
        ({"fps": -1}, "movie: fps must be a number from 0.01 to 240"),
        ({"fps": 0.001}, "movie: fps must be a number from 0.01 to 240"),
        ({"orbit": "x"}, "'orbit' must be a finite number"),
        ({"keyframes": {}}, "'keyframes' must be a list"),
        ({"keyframes": [{"time": 0}]}, "keyframe 0 must be an object"),
        ({"keyframes": [{"time": 2, "camera": {}}]}, "keyframe 0: 'time' must be a number in \\[0, 1\\]"),
        ({"keyframes": [{"time": 0, "camera": {"spin": 1}}]}, "keyframe 0: unknown camera keys"),
        ({"keyframes": [{"time": 0, "camera": {}, "zoom": 1}]}, "keyframe 0: unknown keys"),
        (
            {"keyframes": [{"time": 0, "transfer_function": {"kind": "3d"}}]},
            "keyframe 0: unknown transfer-function",
        ),
        ({"speed": 1}, "unknown keys \\['speed'\\]"),
        ({"frames": 10**400}, "movie: frames must be a whole number"),
        ({"fps": -(10**400)}, "movie: fps must be a number from 0.01 to 240"),
        ({"orbit": 10**400}, "movie: 'orbit' must be a finite number"),
        (
            {"keyframes": [{"time": 10**400, "camera": {}}]},
            "keyframe 0: 'time' must be a number in \\[0, 1\\]",
        ),
        (
            {"keyframes": [{"time": 0, "camera": {"azimuth": 10**400}}]},
            "keyframe 0: camera azimuth must be a finite",
        ),
        (
            {"keyframes": [{"time": 0, "camera": {"elevation": -(10**400)}}]},
            "keyframe 0: camera elevation must be",
        ),
        (
            {"keyframes": [{"time": 0, "camera": {"zoom": 10**400}}]},
            "keyframe 0: camera zoom must be a finite",
        ),
    ],
)
def test_from_dict_errors_are_one_line_naming_the_part(data, message):
    with pytest.raises(VolrenError, match=message) as exc:
        Animation.from_dict(data)
    assert "\n" not in str(exc.value)


@pytest.mark.parametrize(
    "fields, message",
    [
        ({"frames": 10**400}, "frames must be a whole number"),
        ({"fps": 10**400}, "fps must be a number from 0.01 to 240"),
        ({"orbit_degrees": -(10**400)}, "orbit_degrees must be a finite number"),
        ({"orbit_degrees": "90"}, "orbit_degrees must be a finite number"),
        ({"camera_keys": (CameraKey(10**400, OrbitView()),)}, "keyframe time must be a number in \\[0, 1\\]"),
        (
            {"tf_keys": (TFKey(-(10**400), TransferFunction1D.ramp(0, 1)),)},
            "keyframe time must be a number in",
        ),
    ],
)
def test_numbers_beyond_a_float_given_to_animation_are_one_line_errors(fields, message):
    with pytest.raises(VolrenError, match=message) as exc:
        Animation(**fields)
    assert "\n" not in str(exc.value) and len(str(exc.value)) < 150


def test_blended_1d_widgets_draw_the_blend_of_their_1d_tfs():
    a = _tf1d([[0.1, 0.0], [0.5, 0.9], [0.5, 0.2], [0.8, 0.0]], [[0, 1, 0, 0], [1, 0, 0, 1]], 1.0)
    b = _tf1d([[0.3, 0.6], [0.9, 0.1]], [[0.2, 0, 1, 0]], 1.0)
    mix_1d = blend_transfer_functions(a, b, 0.25)
    widgets = [TransferFunction2D((0, 1), (0, 2), [TFWidget.from_1d(tf, (0, 2))]) for tf in (a, b)]
    mix_2d = blend_transfer_functions(*widgets, 0.25)
    s = np.concatenate([np.linspace(-0.5, 1.5, 81), [0.5 - 1e-9, 0.5 + 1e-9]])
    rgb, alpha = mix_2d.sample(s, 1.0)
    np.testing.assert_allclose(alpha, mix_1d.sample(s)[1], atol=1e-12, rtol=0)
    np.testing.assert_allclose(rgb, mix_1d.sample(s)[0], atol=1e-12, rtol=0)
