"""View-direction buttons and the viewport's overlays (outline, orientation axes, colour legend):
the Qt-free camera and projection math against independent oracles, then the real window's
actions and the pixels they put on screen."""

from __future__ import annotations

import numpy as np
import pytest

from tests.app.viewport_pixels import frame_rect, grab
from volren.app.core.loading import LoadedInput
from volren.app.core.overlay_geometry import BOX_EDGES, outline_segments, project_points, triad_arms
from volren.app.core.view_directions import VIEW_DIRECTIONS, look_along, view_direction
from volren.app.rendering.overlays import (
    AXIS_COLORS,
    LEGEND_TEXT_COLOR,
    OPACITY_COLOR,
    OPACITY_WIDTH,
    TRIAD_LENGTH,
    legend_bar_rect,
    range_texts,
    triad_origin,
)
from volren.errors import VolrenError
from volren.model.camera import Camera, bounds_corners
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TFWidget, TransferFunction2D
from volren.model.volume import UniformVolume

pytestmark = pytest.mark.qt

FRAME_TIMEOUT_MS = 20000
#: An off-centre box with three different extents: aspects and centres cannot come out right by luck.
BOUNDS = (-1.0, 3.0, 0.5, 2.5, 4.0, 5.0)
#: (direction, view up) of each button, as ParaView sets them.
EXPECTED = {
    "+X": ((1, 0, 0), (0, 0, 1)),
    "-X": ((-1, 0, 0), (0, 0, 1)),
    "+Y": ((0, 1, 0), (0, 0, 1)),
    "-Y": ((0, -1, 0), (0, 0, 1)),
    "+Z": ((0, 0, 1), (0, 1, 0)),
    "-Z": ((0, 0, -1), (0, 1, 0)),
}


def centre(bounds) -> np.ndarray:
    b = np.asarray(bounds, dtype=float)
    return (b[0::2] + b[1::2]) / 2.0


def eye_depths(camera: Camera, bounds) -> np.ndarray:
    """Distances of the box's corners in front of the camera along its direction."""
    return (bounds_corners(bounds) - np.asarray(camera.position)) @ camera.direction


# ------------------------------------------------------------------------------ view directions
@pytest.mark.parametrize("parallel", [False, True])
@pytest.mark.parametrize("name", list(EXPECTED))
def test_each_view_direction_looks_along_its_axis_at_the_centre_keeping_distance_and_zoom(name, parallel):
    start = Camera.orbit(BOUNDS, 30.0, 20.0, 1.7, parallel=parallel).dolly(0.8).pan(0.3, -0.2)
    cam = look_along(start, view_direction(name), BOUNDS)
    direction, up = EXPECTED[name]
    assert np.allclose(cam.direction, direction, atol=1e-12)
    assert np.allclose(cam.focal_point, centre(BOUNDS), atol=1e-12)
    assert cam.distance == pytest.approx(start.distance, rel=1e-12)
    assert cam.view_up == tuple(float(v) for v in up)
    assert (cam.view_angle, cam.parallel, cam.parallel_scale) == (
        start.view_angle,
        parallel,
        start.parallel_scale,
    )
    near, far = cam.clipping_range
    depths = eye_depths(cam, BOUNDS)
    assert near < depths.min() and far > depths.max(), "the clipping range must enclose the box"


def test_view_directions_are_paraviews_six_in_its_order_and_unknown_names_are_refused():
    assert [v.name for v in VIEW_DIRECTIONS] == list(EXPECTED)
    assert view_direction("+Z").description == "Set view direction to +Z (Y up)"
    assert view_direction("-Y").description == "Set view direction to -Y (Z up)"
    with pytest.raises(VolrenError, match="unknown view direction"):
        view_direction("A")
    with pytest.raises(VolrenError, match="cannot look at bounds"):
        look_along(Camera(), view_direction("+X"), (1.0, 0.0, 0.0, 1.0, 0.0, 1.0))


# ---------------------------------------------------------------------------------- projection
def test_outline_corners_lie_on_the_rays_through_their_pixels():
    """Independent of the projection code: `Camera.rays` unprojects a pixel; the ray through the
    pixel an outline corner lands on must pass through that corner."""
    cam = Camera.orbit(BOUNDS, 30.0, 20.0, 1.2).roll(12.0)
    width, height = 400, 300
    segments = outline_segments(cam, width / height, (0.0, 0.0, float(width), float(height)), BOUNDS)
    assert segments.shape == (12, 2, 2)
    corners = bounds_corners(BOUNDS)
    for (i, j), (a, b) in zip(BOX_EDGES, segments, strict=True):
        assert np.count_nonzero(corners[i] != corners[j]) == 1, "an edge joins corners differing in one axis"
        for corner, pixel in ((corners[i], a), (corners[j], b)):
            origin, direction = cam.rays(width, height, pixel[0] - 0.5, pixel[1] - 0.5)
            off_ray = np.linalg.norm(np.cross(corner - origin, direction))
            assert off_ray < 1e-9, f"corner {corner} is {off_ray} off the ray through its pixel {pixel}"


@pytest.mark.parametrize("parallel", [False, True])
def test_after_a_plus_z_view_the_outline_is_axis_aligned_rectangles_with_the_boxs_aspect(parallel):
    cam = look_along(Camera.orbit(BOUNDS, parallel=parallel), view_direction("+Z"), BOUNDS)
    rect = (10.0, 20.0, 640.0, 480.0)
    pixels = project_points(cam, 640.0 / 480.0, rect, bounds_corners(BOUNDS))
    dx, dy = BOUNDS[1] - BOUNDS[0], BOUNDS[3] - BOUNDS[2]
    for face in (pixels[:4], pixels[4:]):  # z = zmin, z = zmax; corners x fastest
        xs, ys = face[:, 0], face[:, 1]
        assert np.allclose(xs[[0, 2]], xs[0]) and np.allclose(xs[[1, 3]], xs[1]), "vertical sides"
        assert np.allclose(ys[[0, 1]], ys[0]) and np.allclose(ys[[2, 3]], ys[2]), "horizontal sides"
        # Looking along +Z with Y up, +X points left on screen and +Y up.
        assert xs[1] < xs[0] and ys[2] < ys[0]
        assert (xs[0] - xs[1]) / (ys[0] - ys[2]) == pytest.approx(dx / dy, rel=1e-9)
        assert face.mean(axis=0) == pytest.approx((10.0 + 320.0, 20.0 + 240.0), abs=1e-9), (
            "centred in the rect"
        )
    near_face, far_face = pixels[:4], pixels[4:]  # zmin is nearer when looking along +Z
    if parallel:
        assert np.allclose(near_face, far_face), "a parallel projection draws both faces on each other"
    else:
        assert np.ptp(near_face[:, 0]) > np.ptp(far_face[:, 0]), "perspective: the nearer face is larger"


def test_edges_behind_the_near_plane_are_cut_at_it_or_left_out():
    box = (-1.0, 1.0, -1.0, 1.0, -1.0, 1.0)
    # Inside the box at z = 0.5 looking toward -z, near plane 0.1 ahead (at z = 0.4).
    cam = Camera(position=(0.0, 0.0, 0.5), focal_point=(0.0, 0.0, -1.0), clipping_range=(0.1, 10.0))
    width, height = 300, 300
    segments = outline_segments(cam, 1.0, (0.0, 0.0, float(width), float(height)), box)
    assert len(segments) == 8, "the four edges of the z = 1 face lie behind the camera"
    assert np.all(np.isfinite(segments))
    corners = bounds_corners(box)
    cut_points = [(corners[i][0], corners[i][1], 0.4) for i, j in BOX_EDGES if corners[i][2] != corners[j][2]]
    ends = segments.reshape(-1, 2)
    for point in cut_points:  # each z edge now ends where it meets the near plane
        dist = [np.linalg.norm(np.cross(point - o, d)) for o, d in
                (cam.rays(width, height, x - 0.5, y - 0.5) for x, y in ends)]  # fmt: skip
        assert min(dist) < 1e-9, f"no edge ends at {point}"


def test_triad_arms_are_the_world_axes_as_a_parallel_camera_draws_them():
    """Oracle: a parallel camera moves the focal point's image by (H / 2 / scale) pixels per unit
    along each world axis, in the same screen direction the triad's arm must point."""
    cam = Camera.orbit(BOUNDS, 40.0, -25.0, parallel=True).roll(20.0)
    height = 500.0
    rect = (0.0, 0.0, 700.0, height)
    fp = np.asarray(cam.focal_point)
    ends = project_points(cam, 700.0 / height, rect, fp + np.eye(3))
    expected = (ends - project_points(cam, 700.0 / height, rect, fp[None])) * (
        2.0 * cam.parallel_scale / height
    )
    offsets, order = triad_arms(cam, 10.0)
    assert np.allclose(offsets, 10.0 * expected, atol=1e-9)
    depth = np.eye(3) @ -cam.direction  # toward the viewer
    assert list(order) == list(np.argsort(depth)), "farthest arm first"


@pytest.mark.parametrize(
    ("name", "arms", "first"),
    [  # looking along +Z with Y up, X points left and Z away (drawn first, under the others)
        ("+Z", [(-1, 0), (0, -1), (0, 0)], 2),
        ("-Z", [(1, 0), (0, -1), (0, 0)], 0),
        ("+X", [(0, 0), (-1, 0), (0, -1)], 0),
    ],
)
def test_triad_after_view_directions(name, arms, first):
    cam = look_along(Camera.orbit(BOUNDS), view_direction(name), BOUNDS)
    offsets, order = triad_arms(cam, 7.0)
    assert np.allclose(offsets, 7.0 * np.asarray(arms, dtype=float), atol=1e-12)
    assert order[0] == first


# ------------------------------------------------------------------------------------- widgets
def box_volume() -> UniformVolume:
    """A smooth field over an off-centre box 1.6 x 0.8 x 0.5 (x, y, z)."""
    z, y, x = np.mgrid[0:6, 0:9, 0:17].astype(np.float32)
    return UniformVolume(np.sin(x / 4) + np.cos(y / 3) + z / 5, spacing=(0.1, 0.1, 0.1), origin=(-0.5, 0.2, 0.1),
                         name="box")  # fmt: skip


@pytest.fixture
def shown(window, fake_2d, qtbot):
    """The window showing `box_volume` with the constant-colour renderer, a full frame on screen."""
    tf = TransferFunction1D([[0.0, 0.1, 0.2, 0.9], [1.0, 0.9, 0.8, 0.1], [2.5, 0.2, 0.9, 0.3]],
                            [[0.0, 0.0], [1.2, 0.8], [2.5, 0.3]])  # fmt: skip
    with qtbot.waitSignal(window.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        window.files.apply_loaded(LoadedInput(box_volume(), tf, source="box"), "fake_2d")
    return window


def show_view(window, qtbot, name: str) -> None:
    with qtbot.waitSignal(window.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        window.view_direction_actions[name].trigger()


def projected_corners(camera: Camera, aspect: float, rect, bounds) -> np.ndarray:
    """The box's corners in widget pixels, straight from the camera's matrices."""
    clip = (
        np.c_[bounds_corners(bounds), np.ones(8)]
        @ (camera.projection_matrix(aspect) @ camera.view_matrix()).T
    )
    ndc = clip[:, :2] / clip[:, 3:]
    x, y, w, h = rect
    return np.c_[x + (ndc[:, 0] + 1) / 2 * w, y + (1 - ndc[:, 1]) / 2 * h]


def near(pixels: np.ndarray, point, color, radius: int = 1, tolerance: int = 0) -> bool:
    """Whether a pixel of `color` lies within `radius` pixels of `point` (x, y)."""
    x, y = (int(np.floor(v)) for v in point)
    patch = pixels[max(y - radius, 0) : y + radius + 1, max(x - radius, 0) : x + radius + 1].astype(int)
    return bool(np.any(np.abs(patch - np.asarray(color)).max(axis=-1) <= tolerance))


WHITE = (255, 255, 255)


def test_view_direction_actions_sit_in_the_view_menu_and_toolbar_disabled_without_a_volume(
    window, fake_2d, qtbot
):
    actions = window.view_direction_actions
    assert list(actions) == list(EXPECTED)
    assert [a.text() for a in actions.values()] == list(EXPECTED)
    assert window.view_direction_menu.title().replace("&", "") == "View direction"
    assert window.view_direction_menu.menuAction() in window.view_menu.actions()
    assert window.view_direction_menu.actions()[:6] == list(actions.values())
    assert all(a in window.toolbar.actions() for a in actions.values())
    assert not any(a.isEnabled() for a in actions.values()), "no volume: nothing to look at"
    before = window.state.camera
    actions["+X"].trigger()  # disabled: does nothing
    assert window.state.camera is before is None
    with qtbot.waitSignal(window.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        window.files.apply_loaded(
            LoadedInput(box_volume(), TransferFunction1D.ramp(0, 2), source="box"), "fake_2d"
        )
    assert all(a.isEnabled() for a in actions.values())


def test_anatomical_views_are_offered_where_the_data_says_how_the_patient_lies(window, fake_2d, qtbot):
    """Issue 23: A/P/L/R/S/I where the data has a patient orientation (here LPS, as DICOM)."""
    actions = window.anatomical_actions
    assert list(actions) == ["A", "P", "L", "R", "S", "I"]
    assert all(a in window.view_direction_menu.actions() for a in actions.values())
    with qtbot.waitSignal(window.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        window.files.apply_loaded(
            LoadedInput(box_volume(), TransferFunction1D.ramp(0, 2), source="box"), "fake_2d"
        )
    assert (
        not any(a.isEnabled() for a in actions.values())
        and "nothing of how the patient lies" in actions["A"].toolTip()
    )
    values = box_volume().values
    patient = UniformVolume(values, spacing=(0.4, 0.2, 0.3), patient_axes=("L", "P", "S"), name="ct")
    with qtbot.waitSignal(window.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        window.files.apply_loaded(LoadedInput(patient, TransferFunction1D.ramp(0, 2), source="ct"), "fake_2d")
    assert all(a.isEnabled() for a in actions.values())
    assert actions["S"].toolTip() == "View from the patient's superior side (A up)"
    distance = window.state.camera.distance
    for letter, direction, up in (
        ("A", (0, 1, 0), (0, 0, 1)),
        ("L", (-1, 0, 0), (0, 0, 1)),
        ("I", (0, 0, 1), (0, -1, 0)),
    ):
        with qtbot.waitSignal(window.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
            actions[letter].trigger()
        camera = window.state.camera
        assert np.allclose(camera.direction, direction, atol=1e-12) and camera.view_up == tuple(
            map(float, up)
        ), letter
        assert np.allclose(camera.focal_point, centre(patient.bounds)) and camera.distance == pytest.approx(
            distance
        )


def test_view_direction_actions_turn_the_camera_to_the_cropped_volumes_centre(shown, qtbot):
    w = shown
    for name, (direction, up) in EXPECTED.items():
        before = w.state.camera
        show_view(w, qtbot, name)
        cam = w.state.camera
        assert np.allclose(cam.direction, direction, atol=1e-12), name
        assert cam.view_up == tuple(float(v) for v in up), name
        assert np.allclose(cam.focal_point, centre(w.state.volume.bounds), atol=1e-12), name
        assert cam.distance == pytest.approx(before.distance, rel=1e-12), name
        assert w.viewport.frame.camera == cam, "the new view was rendered"
    box = (-0.3, 0.9, 0.2, 0.6, 0.1, 0.4)
    w.state.set_crop(box)
    show_view(w, qtbot, "+X")
    assert np.allclose(w.state.camera.focal_point, centre(w.state.render_volume.bounds), atol=1e-12)
    assert np.allclose(w.state.camera.focal_point, centre(box), atol=1e-6)


def test_overlay_actions_toggle_flags_and_repaint_without_rendering(shown, fake_2d, qtbot, monkeypatch):
    w = shown
    actions = w.overlay_actions
    assert {n: a.text() for n, a in actions.items()} == {
        "outline": "Outline", "axes": "Orientation axes", "legend": "Colour legend"}  # fmt: skip
    assert all(a.isCheckable() and a in w.view_menu.actions() for a in actions.values())
    assert {n: a.isChecked() for n, a in actions.items()} == {"outline": True, "axes": True, "legend": False}
    assert (w.viewport.overlays.outline, w.viewport.overlays.axes, w.viewport.overlays.legend) == (
        True,
        True,
        False,
    )
    qtbot.wait(100)
    renders = len(fake_2d.calls)
    updates = []
    monkeypatch.setattr(w.viewport, "update", lambda *args: updates.append(args))
    for name, action in actions.items():
        was = getattr(w.viewport.overlays, name)
        action.trigger()
        assert getattr(w.viewport.overlays, name) is (not was) and action.isChecked() is (not was)
        assert len(updates) == 1, f"toggling {name} must repaint the viewport"
        updates.clear()
    qtbot.wait(150)
    assert len(fake_2d.calls) == renders, "toggling an overlay must not render a frame"
    with pytest.raises(ValueError, match="unknown overlay"):
        w.viewport.set_overlay("grid", True)


@pytest.mark.parametrize("view", [None, "+Z", "-Y"])
def test_outline_is_drawn_at_the_projected_corners_and_goes_when_toggled_off(shown, qtbot, view):
    w = shown
    if view is not None:
        show_view(w, qtbot, view)
    frame = w.viewport.frame
    assert frame.camera == w.state.camera
    corners = projected_corners(
        frame.camera, frame.width / frame.height, frame_rect(w.viewport), w.state.volume.bounds
    )
    pixels = grab(w.viewport)
    for i, j in BOX_EDGES:
        for point in (corners[i], corners[j], (corners[i] + corners[j]) / 2):
            assert near(pixels, point, WHITE), f"no outline at {point} ({view} view)"
    w.overlay_actions["outline"].trigger()
    off = grab(w.viewport)
    assert not np.any(np.all(off == WHITE, axis=-1)), "the outline is off: nothing white"
    w.overlay_actions["outline"].trigger()
    assert np.array_equal(grab(w.viewport), pixels)


def test_outline_follows_the_crop_box(shown, qtbot):
    w = shown
    box = (-0.3, 0.9, 0.2, 0.6, 0.1, 0.4)
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.state.set_crop(box)
    frame = w.viewport.frame
    aspect, rect = frame.width / frame.height, frame_rect(w.viewport)
    pixels = grab(w.viewport)
    cropped = projected_corners(frame.camera, aspect, rect, w.state.render_volume.bounds)
    whole = projected_corners(frame.camera, aspect, rect, w.state.volume.bounds)
    assert all(near(pixels, p, WHITE) for p in cropped)
    assert not any(near(pixels, p, WHITE, radius=0) for p in whole), "the whole volume's outline is gone"


def reddish(pixels, point, channel: int, radius: int = 1) -> bool:
    """Whether a pixel near `point` is clearly of the axis colour `channel` (0 red, 1 green, 2 blue)."""
    x, y = (int(np.floor(v)) for v in point)
    patch = pixels[y - radius : y + radius + 1, x - radius : x + radius + 1].astype(int).reshape(-1, 3)
    others = np.delete(patch, channel, axis=1)
    return bool(np.any((patch[:, channel] > 150) & (patch[:, channel] - others.max(axis=1) > 70)))


@pytest.mark.parametrize(("view", "arms"), [("+Z", {0: (-1, 0), 1: (0, -1)}), ("-Z", {0: (1, 0), 1: (0, -1)}),
                                            ("+X", {1: (-1, 0), 2: (0, -1)})])  # fmt: skip
def test_orientation_axes_turn_with_the_camera_in_the_lower_left_corner(shown, qtbot, view, arms):
    w = shown
    show_view(w, qtbot, view)
    origin = triad_origin(w.viewport.height())
    o = np.array([origin.x(), origin.y()])
    assert o[0] < 0.2 * w.viewport.width() and o[1] > 0.8 * w.viewport.height(), "lower left"
    pixels = grab(w.viewport)
    for axis, (dx, dy) in arms.items():
        along = o + 0.6 * TRIAD_LENGTH * np.array([dx, dy])
        against = o - 0.6 * TRIAD_LENGTH * np.array([dx, dy])
        assert reddish(pixels, along, axis), f"axis {'XYZ'[axis]} should point {(dx, dy)} in the {view} view"
        assert not reddish(pixels, against, axis)
    assert AXIS_COLORS[0].red() > 200 and AXIS_COLORS[1].green() > 200 and AXIS_COLORS[2].blue() > 200
    w.overlay_actions["axes"].trigger()
    off = grab(w.viewport)
    for axis, (dx, dy) in arms.items():
        assert not reddish(off, o + 0.6 * TRIAD_LENGTH * np.array([dx, dy]), axis)


def test_colour_legend_shows_the_tfs_colours_opacity_and_range_and_hides_for_a_2d_tf(shown, qtbot):
    w = shown
    vp = w.viewport
    tf = w.state.transfer_function
    before = grab(vp)
    w.overlay_actions["legend"].trigger()
    pixels = grab(vp)
    bar = legend_bar_rect(vp.width(), vp.height())
    assert bar.right() > 0.9 * vp.width(), "at the right edge"
    lo, hi = tf.value_range
    assert (lo, hi) == (0.0, 2.5)
    assert range_texts((lo, hi)) == ("2.5", "0")
    x = int(bar.center().x())
    for share in (0.1, 0.3, 0.5, 0.7, 0.9):  # colours: the maximum on top
        y = bar.top() + share * bar.height()
        rgb, _ = tf.sample(hi - share * (hi - lo))
        assert np.abs(pixels[int(y), x].astype(int) - np.round(rgb * 255)).max() <= 4, (
            f"bar colour at {share}"
        )
    curve_left = bar.left() - 3.0 - OPACITY_WIDTH
    for share in (0.2, 0.5, 0.52, 0.8):  # opacity: a curve beside the bar, 0 at its left, 1 at its right
        y = bar.top() + share * bar.height()
        _, alpha = tf.sample(hi - share * (hi - lo))
        expected_x = curve_left + float(alpha) * OPACITY_WIDTH
        assert near(pixels, (expected_x, y), OPACITY_COLOR.getRgb()[:3], radius=2, tolerance=60), (
            f"opacity at {share}"
        )
    for top in (bar.top() - 20, bar.bottom() + 4):  # the range's numbers above and below the bar
        region = pixels[int(top) : int(top) + 16, int(bar.left()) - 30 : int(bar.right()) + 1].astype(int)
        text = np.abs(region - np.asarray(LEGEND_TEXT_COLOR.getRgb()[:3])).max(axis=-1) < 40
        assert np.count_nonzero(text) >= 3, "the range's number is written there"
    outside = np.ones(pixels.shape[:2], bool)
    outside[int(bar.top()) - 24 : int(bar.bottom()) + 24, int(curve_left) - 200 :] = False
    assert np.array_equal(pixels[outside], before[outside]), "the legend draws only beside the right edge"

    widget = TFWidget.box((0.5, 2.0), (0.0, 1.0), (1.0, 0.0, 0.0), 0.5)
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.state.set_transfer_function(TransferFunction2D((0.0, 2.5), (0.0, 1.0), [widget]))
    assert np.array_equal(grab(vp), before), "a 2D TF has no colour per value: no legend"


# --------------------------------------------------------------------- against a real renderer
def convex_hull(points: np.ndarray) -> np.ndarray:
    """The convex hull of 2D points, counter-clockwise in a y-up sense (Andrew's monotone chain)."""
    pts = sorted(map(tuple, points))

    def turn(o, a, b) -> float:
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    def half(seq):
        out: list = []
        for p in seq:
            while len(out) >= 2 and turn(out[-2], out[-1], p) <= 0:
                out.pop()
            out.append(p)
        return out[:-1]

    return np.array(half(pts) + half(pts[::-1]))


def signed_distance(hull: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Distance outside (> 0) or inside (< 0) a convex polygon, per pixel centre (exact inside)."""
    d = np.full(x.shape, -np.inf)
    for a, b in zip(hull, np.roll(hull, -1, axis=0), strict=True):
        edge = b - a
        normal = np.array([edge[1], -edge[0]]) / np.linalg.norm(edge)  # outward for this winding
        d = np.maximum(d, (x - a[0]) * normal[0] + (y - a[1]) * normal[1])
    return d


@pytest.mark.vtk
@pytest.mark.parametrize("view", [None, "+Y"])
def test_outline_hugs_the_volume_the_vtk_renderer_draws(make_window, qtbot, view):
    """End to end: with an opaque TF the vtk renderer fills exactly the box's projection, and the
    outline's projected corners span that silhouette: every pixel whose centre lies more than a
    pixel inside it is drawn, none more than a pixel outside (measured: a fraction of a pixel)."""
    w = make_window()
    tf = TransferFunction1D.constant(1.0, (1.0, 0.2, 0.2), opacity_unit_distance=0.001)
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.files.apply_loaded(LoadedInput(box_volume(), tf, source="box"), "vtk")
    if view is not None:
        show_view(w, qtbot, view)
    frame = w.viewport.frame
    rendered = (
        np.abs(frame.rgb.astype(int) - np.round(np.asarray(w.state.background) * 255)).max(axis=-1) > 40
    )
    corners = project_points(frame.camera, frame.width / frame.height, (0.0, 0.0, frame.width, frame.height),
                             bounds_corners(w.state.volume.bounds))  # fmt: skip
    yy, xx = np.mgrid[0 : frame.height, 0 : frame.width] + 0.5
    sd = signed_distance(convex_hull(corners), xx, yy)
    assert np.count_nonzero(rendered) > 0.05 * rendered.size
    assert not np.any(rendered & (sd > 1.0)), "the renderer drew outside the outline"
    assert not np.any(~rendered & (sd < -1.0)), "the renderer left a gap inside the outline"
