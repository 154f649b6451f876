"""The app's Qt-free parts: view state, camera gestures, pixel conversion, renderer choice."""

from __future__ import annotations

import math

import numpy as np
import pytest

from volren.app.core import interaction
from volren.app.core.frame_sizes import FrameCost, adaptive_preview_scale, preview_size
from volren.app.core.renderer_choice import RendererOption, pick_renderer, renderer_options
from volren.app.core.state import Change, ViewState, default_camera
from volren.io.image_io import to_png_pixels
from volren.model.camera import Camera
from volren.samples import marschner_lobb, sample_transfer_functions

BOUNDS = (-1.0, 1.0, -1.0, 1.0, -1.0, 1.0)


@pytest.fixture
def state() -> tuple[ViewState, list[Change]]:
    s = ViewState()
    changes: list[Change] = []
    s.subscribe(changes.append)
    volume = marschner_lobb(9)
    s.load(volume, sample_transfer_functions()["marschner_lobb"], default_camera(volume), source="ml")
    return s, changes


def test_state_announces_each_change(state):
    s, changes = state
    assert changes == [Change("volume", False)]
    s.set_camera(s.camera.zoom(2.0))
    s.set_renderer("reference")
    s.set_renderer("reference")  # no change, no announcement
    s.transfer_function.set_opacity_unit_distance(0.2)  # in-place edit
    assert [c.what for c in changes[1:]] == ["camera", "renderer", "tf"]
    assert not any(c.interactive for c in changes)


def test_changes_during_an_interaction_are_interactive(state):
    s, changes = state
    s.begin_interaction()
    s.set_camera(s.camera.azimuth(5))
    s.transfer_function.set_opacity_unit_distance(0.3)
    s.end_interaction()
    with s.interaction():
        s.set_camera(s.camera.azimuth(5))
    assert changes[1:] == [
        Change("camera", True),
        Change("tf", True),
        Change("interaction", False),
        Change("camera", True),
    ]


def test_replacing_the_tf_unhooks_the_old_one(state):
    s, changes = state
    old = s.transfer_function
    s.set_transfer_function(old.copy())
    n = len(changes)
    old.set_opacity_unit_distance(0.5)
    assert len(changes) == n, "edits of a TF no longer shown must not trigger frames"


def test_reset_uses_the_scene_convention(state):
    s, _ = state
    s.set_camera(s.camera.azimuth(40).dolly(2))
    s.reset_camera(aspect=1.5)
    assert s.camera == Camera.orbit(s.volume.bounds, 30, 20, 1, False, 1.5)


def test_rotate_follows_vtk_trackball():
    cam = Camera.orbit(BOUNDS)
    # a drag across the whole width is 200 degrees of azimuth (mouse right -> negative azimuth)
    turned = interaction.rotate(cam, 100, 0, 100, 100, BOUNDS)
    expected = cam.azimuth(-200).orthogonalize_view_up().reset_clipping_range(BOUNDS)
    assert np.allclose(turned.position, expected.position)
    # dragging down raises the camera (Qt's y points down)
    up = interaction.rotate(cam, 0, 10, 100, 100, BOUNDS)
    assert up.position[1] > cam.position[1]
    assert abs(np.dot(up.view_up, up.direction)) < 1e-12
    assert interaction.rotate(cam, 0, 0, 100, 100, BOUNDS) == cam.reset_clipping_range(BOUNDS)


def test_dolly_and_wheel_factors():
    cam = Camera.orbit(BOUNDS)
    assert interaction.wheel_dolly_factor(120) == pytest.approx(1.1**2)
    assert interaction.drag_dolly_factor(-50, 100) == pytest.approx(1.1**10)
    closer = interaction.dolly(cam, 2.0, BOUNDS)
    assert closer.distance == pytest.approx(cam.distance / 2)
    assert closer.clipping_range[0] < closer.distance - math.sqrt(3), (
        "near plane must stay in front of the data"
    )
    flat = Camera.orbit(BOUNDS, parallel=True)
    zoomed = interaction.dolly(flat, 2.0, BOUNDS)
    assert (
        zoomed.parallel_scale == pytest.approx(flat.parallel_scale / 2) and zoomed.distance == flat.distance
    )


def test_pan_moves_the_scene_with_the_mouse():
    cam = Camera.orbit(BOUNDS)
    moved = interaction.pan(cam, 10, 0, 100, BOUNDS)
    side = np.cross(cam.direction, cam.view_up)  # screen right
    shift = np.subtract(moved.focal_point, cam.focal_point)
    # the camera moves left, so the scene appears to move right
    assert np.dot(shift, side) == pytest.approx(-10 * interaction.world_per_pixel(cam, 100))
    assert np.allclose(np.subtract(moved.position, cam.position), shift)


def test_composite_over_background():
    rgba = np.zeros((2, 3, 4), np.float32)
    rgba[0, 0] = (0.5, 0.25, 0.0, 0.5)  # premultiplied
    rgba[1, 2] = (1.0, 1.0, 1.0, 1.0)
    out = to_png_pixels(rgba, (0.2, 0.4, 0.6))
    assert out.dtype == np.uint8 and out.shape == (2, 3, 3) and out.flags.c_contiguous
    assert tuple(out[0, 0]) == (153, 115, 77)  # rgb + (1 - a) * bg
    assert tuple(out[0, 1]) == (51, 102, 153)
    assert tuple(out[1, 2]) == (255, 255, 255)
    assert tuple(to_png_pixels(rgba)[0, 0]) == (128, 64, 0)
    assert preview_size(641, 480, 0.5) == (320, 240) and preview_size(1, 1, 0.5) == (1, 1)


def test_preview_scale_adapts_to_renderer_cost():
    assert adaptive_preview_scale(None, 10000) == 0.5
    assert adaptive_preview_scale(1e-5, 100_000) == 0.5  # 1 ms full frames: a quarter of the pixels
    slow = adaptive_preview_scale(400 / 700_000, 700_000)  # 400 ms full frames
    assert slow == pytest.approx((50 / 400) ** 0.5) and 0.1 < slow < 0.5
    assert adaptive_preview_scale(18000 / 700_000, 700_000) == 0.1  # the reference renderer: 18 s


def test_a_fixed_cost_over_the_budget_keeps_previews_at_a_quarter_of_the_pixels():
    # a software-GL slicer: 100 ms whatever the size, plus a little per pixel
    assert adaptive_preview_scale(1e-5, 700_000, fixed_ms=100.0) == 0.5
    # half the budget fixed: the per-pixel part gets the other half
    scale = adaptive_preview_scale(400 / 700_000, 700_000, fixed_ms=25.0)
    assert scale == pytest.approx((25 / 400) ** 0.5)


def test_frame_cost_fits_fixed_and_per_pixel_parts_from_full_frames_and_the_latest_previews():
    cost = FrameCost()
    assert cost.model() is None
    cost.note(40_000, 80.0)
    assert cost.model() == (0.0, 80.0 / 40_000)  # full frames only: all per pixel
    cost.note(10_000, 50.0)  # a preview: 30 ms less for 30,000 fewer pixels
    fixed, per_pixel = cost.model()
    assert per_pixel == pytest.approx(1e-3) and fixed == pytest.approx(40.0)
    cost.note(40_000, 500.0)  # a full frame that also paid a TF edit's reclassification: the fastest counts
    assert cost.model() == pytest.approx((40.0, 1e-3))
    cost.note(12_000, 52.0)  # a newer preview size replaces the older one
    assert cost.model() == pytest.approx((40.0, 28.0 / 28_000))  # 28 ms less for 28,000 fewer pixels
    cost.note(25_000, 79.0)  # a preview over half the full frame's pixels: no fit, all per pixel
    assert cost.model() == (0.0, 80.0 / 40_000)
    # the largest size drawn twice, each paying something once (shear-warp's first frames along
    # a new axis), then steady previews two thirds its size: these set the rate
    cost = FrameCost()
    cost.note(120_000, 118.0)
    cost.note(120_000, 688.0)
    assert cost.model() == (0.0, 118.0 / 120_000)
    for ms in (52.0, 47.0, 50.0):
        cost.note(81_000, ms)
    assert cost.model() == (0.0, 47.0 / 81_000)


def test_frame_cost_forgets_a_largest_size_whose_times_previews_contradict():
    """A 2D TF drag's trace on bonsai: the largest preview size paid a table build at each of its
    frames, then previews of 8,550 pixels took 25 ms. A line through both meets zero pixels below
    zero ms (the cost grew faster than the pixels), which only once-paid times explain: the
    previews become the reference, so the next size is sized from what they cost."""
    cost = FrameCost()
    cost.note(22_484, 176.0)
    cost.note(22_484, 184.0)
    cost.note(8_550, 25.0)
    assert cost.model() == (0.0, 25.0 / 8_550)
    full = 947 * 896
    scale = adaptive_preview_scale(cost.model()[1], full, 80.0, 0.5, fixed_ms=cost.model()[0])
    assert (scale * scale * full) == pytest.approx(80.0 / (25.0 / 8_550))  # the budget's pixels at that rate
    cost.note(27_000, 78.0)  # the larger preview drawn: the largest size now, at its own rate
    assert cost.model() == (0.0, 78.0 / 27_000)
    # a largest size whose cost is mostly fixed keeps its times: the line meets zero pixels above zero
    cost = FrameCost()
    cost.note(200_000, 60.0)
    cost.note(50_000, 40.0)
    assert cost.model() == pytest.approx((100.0 / 3, 20.0 / 150_000))


def test_frame_cost_forgets_the_first_frames_along_a_new_axis():
    """Shear-warp's rotation previews on bonsai at 947x896: its first two frames at a quarter of the
    pixels paid the slice stacks of a new axis (505 and 411 ms), then previews of about 40,000 pixels
    took 45-62 ms, most of it fixed. The line through both sizes predicted 1.7x what the previews
    took, and sized from it they stayed at 5 % of the pixels. Taken as stale, the previews become
    the reference and grow back to a quarter of the pixels within the gesture."""
    full = 947 * 896
    cost = FrameCost()
    cost.note(212_352, 504.9)
    cost.note(212_352, 410.9)
    cost.note(41_382, 52.3)
    assert cost.model() == (0.0, 52.3 / 41_382)
    scales = []
    for _ in range(12):
        fixed, per_pixel = cost.model()
        scales.append(adaptive_preview_scale(per_pixel, full, 80.0, 0.5, fixed_ms=fixed))
        pixels = round(scales[-1] ** 2 * full)
        cost.note(pixels, 40.0 + 1.5e-4 * pixels)  # what such a preview costs: 40 ms fixed
    assert scales[-1] == 0.5 and scales[0] < 0.3


def test_pick_renderer_keeps_current_else_takes_the_measured_choice():
    opts = [
        RendererOption("reference", None),
        RendererOption("vtk", None),
        RendererOption("slicer", "no tets"),
    ]
    asked = []

    def measured(usable):
        asked.append(usable)
        return "vtk"

    assert pick_renderer(opts, "reference", measured) == "reference" and asked == []
    assert pick_renderer(opts, "slicer", measured) == "vtk" and asked == [["reference", "vtk"]]
    assert (
        pick_renderer(opts, "slicer", lambda usable: None) == "reference"
    )  # nothing measured: the first usable
    assert pick_renderer(opts, "slicer", lambda usable: "slicer") == "reference"  # never an unusable one
    assert pick_renderer([RendererOption("a", "x"), RendererOption("b", None)], "a") == "b"
    assert pick_renderer([RendererOption("a", "x")], "a") is None


def test_renderer_options_lists_every_registered_renderer():
    from volren.renderers.registry import registry

    options, _warnings = renderer_options("uniform")
    assert [o.name for o in options] == registry.names()
    assert next(o for o in options if o.name == "vtk").enabled


def test_loading_a_2d_tf_gives_it_to_the_app(tmp_path):
    """A 2D TF file, a scene with one, or a 2D override all load as the 2D TF they hold."""
    from volren import io
    from volren.app.core.loading import load_input
    from volren.model import TFWidget, TransferFunction2D
    from volren.model.scene import Scene
    from volren.samples import sample_paths

    tf = TransferFunction2D(
        (0.0, 1.0), (0.0, 1.0), [TFWidget.box((0.2, 0.8), (0.0, 1.0), (1.0, 1.0, 1.0), 0.5)]
    )
    io.save_transfer_function(tf, tmp_path / "tf2d.json")
    volume_path, _ = sample_paths("marschner_lobb")
    io.save_scene(Scene(str(volume_path), tf, renderer="reference"), tmp_path / "scene.json")
    for path, tf_path, has_volume in (
        (tmp_path / "tf2d.json", None, False),
        (tmp_path / "scene.json", None, True),
        (volume_path, tmp_path / "tf2d.json", True),
    ):
        loaded = load_input(path, tf_path)
        assert loaded.transfer_function == tf
        assert (loaded.volume is not None) == has_volume
