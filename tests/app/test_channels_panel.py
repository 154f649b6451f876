"""Multi-channel volumes in the app (Max 1995, section 2: a TF per channel, their extinctions and
emissions added): opening an OME-Zarr image with a c axis, the Channels panel, the 1D editor on
the selected channel, and undo of every edit.

The image: 16^3 voxels, channel "A" a box of value 1 at the left (x < 8), channel "B" a box of
value 1 at the right, channel "C" zeros and inactive; ``omero.channels`` gives names, colours (A
red, B green) and windows [0, 1]. Seen along -z with a parallel camera, the left half of the image
shows A and the right half B. The oracle of a frame is the raycast renderer given the TF per
channel the test expects, at the frame's own settings and camera, converted to pixels as the
render service converts them.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from PyQt5.QtGui import QColor

from tests.app.conftest import FRAME_TIMEOUT_MS
from tests.app.renderer_picks import renderer_without
from volren.app.core.loading import load_input
from volren.app.panels.channels import NAME, channel_color
from volren.app.rendering.render_service import tf_key
from volren.io.image_io import to_png_pixels
from volren.model.camera import Camera
from volren.model.channels import ChannelTransferFunction
from volren.model.value_histogram import value_histogram
from volren.renderers.base import render_frame
from volren.renderers.registry import registry

zarr = pytest.importorskip("zarr", reason="volren[zarr] is part of the test set-up")

N = 16
#: The first raycast frame of a process may compile its kernels (numba; minutes on a busy 2-core machine).
FIRST_FRAME_TIMEOUT_MS = 180_000
OMERO = {
    "channels": [
        {"label": "A", "color": "FF0000", "window": {"start": 0, "end": 1}, "active": True},
        {"label": "B", "color": "00FF00", "window": {"start": 0, "end": 1}, "active": True},
        {"label": "C", "color": "0000FF", "window": {"start": 0, "end": 1}, "active": False},
    ]
}


def _values() -> np.ndarray:
    values = np.zeros((3, N, N, N), np.float32)
    values[0, 3:-3, 3:-3, 3:8] = 1.0
    values[1, 3:-3, 3:-3, 8:-3] = 1.0
    return values


@pytest.fixture
def image(tmp_path):
    """The image as an OME-Zarr folder (axes c, z, y, x; one level)."""
    path = tmp_path / "cells.zarr"
    group = zarr.open_group(str(path), mode="w", zarr_format=2)
    values = _values()
    group.create_array("0", shape=values.shape, chunks=(1, 8, N, N), dtype="float32")[:] = values
    group.attrs["multiscales"] = [{
        "version": "0.4",
        "axes": [{"name": a} for a in "czyx"],
        "datasets": [{"path": "0", "coordinateTransformations": [{"type": "scale", "scale": [1.0] * 4}]}],
    }]  # fmt: skip
    group.attrs["omero"] = OMERO
    return path


def _current(window):
    def check(frame) -> bool:
        return (
            frame.tf_key == tf_key(window.state.drawn_transfer_function)
            and frame.renderer == window.state.renderer
        )

    return check


def _frame_after(window, qtbot, action, timeout_ms: int = FRAME_TIMEOUT_MS):
    with qtbot.waitSignal(window.fullFrameShown, timeout=timeout_ms, check_params_cb=_current(window)) as got:
        action()
    return got.args[0]


def _assert_drawn(frame, expected: np.ndarray) -> None:
    """The frame is `expected` to one level of 8 bits: raycast's channel path rounds a few pixels
    differently in a renderer that drew other frames before (its tables are kept) than in a fresh one."""
    assert np.abs(frame.rgb.astype(np.int16) - expected).max() <= 1


def _expected(window, frame, ctf: ChannelTransferFunction) -> np.ndarray:
    with registry.create(frame.renderer) as renderer:
        renderer.set_settings(frame.settings)
        renderer.set_volume(window.state.volume)
        renderer.set_transfer_function(ctf)
        image, _ = render_frame(renderer, frame.camera, frame.width, frame.height)
    return to_png_pixels(image, window.state.background)


@pytest.fixture
def shown(make_window, qtbot, image, error_boxes):
    """A window showing the image, read by the app's loader, with raycast along -z (parallel)."""
    window = make_window()
    window.resize(700, 360)
    # previews by raycast too: these tests are about what is drawn, and another renderer's set-up
    # (a numba compilation on a cold cache) would hold the render thread for minutes
    window.scheduler._failed_previewers.update(
        n for n in registry.names() if n != "raycast"
    )  # a small viewport: fast frames
    loaded = load_input(image)
    _frame_after(window, qtbot, lambda: window.files.apply_loaded(loaded, "raycast"), FIRST_FRAME_TIMEOUT_MS)
    camera = Camera.orbit(loaded.volume.bounds, 0.0, 0.0, 1.0, True, window.viewport.aspect())
    frame = _frame_after(window, qtbot, lambda: window.state.set_camera(camera))
    assert error_boxes == []
    return window, frame


def _halves(frame) -> tuple[np.ndarray, np.ndarray]:
    """Pixel columns that see only channel A (left) and only channel B (right), a voxel's margin in."""
    x = (np.arange(frame.width) + 0.5) / frame.width
    camera = frame.camera
    half_width = camera.parallel_scale * frame.width / frame.height
    world_x = camera.focal_point[0] + (2 * x - 1) * half_width
    return (world_x > 4) & (world_x < 6.5), (world_x > 8.5) & (world_x < N - 5)


def test_opening_lists_the_channels_with_the_files_names_colours_and_active_flags(shown):
    window, frame = shown
    state, panel = window.state, window.docks.channels
    assert state.channels is not None and state.channels_drawn and not panel.note.isVisible()
    assert [panel.name(c) for c in range(panel.count)] == ["A", "B", "C"]
    assert [panel.show_box(c).isChecked() for c in range(3)] == [True, True, False]  # C inactive
    assert [panel.weight_box(c).value() for c in range(3)] == [1.0, 1.0, 1.0]
    ctf = state.channel_transfer_function
    assert [channel_color(tf) for tf in ctf.tfs] == [(1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)]
    _, alpha = ctf.tfs[0].sample(np.array([0.0, 1.0]))
    np.testing.assert_allclose(alpha, [0.0, 0.2])  # the CLI's default ramp over the omero window
    assert state.transfer_function is ctf.tfs[0] and panel.table.currentRow() == 0
    assert frame.settings.preintegration is False
    _assert_drawn(frame, _expected(window, frame, ctf))
    left, right = _halves(frame)
    row = frame.rgb[frame.height // 2]
    assert np.all(row[left][:, 0] > row[left][:, 1]) and np.all(row[right][:, 1] > row[right][:, 0])


def test_the_renderer_box_refuses_renderers_that_mix_no_channels(shown):
    window, _ = shown
    chooser = window.renderers.chooser
    assert chooser.is_enabled("raycast") and window.state.renderer == "raycast"
    lacking = renderer_without("channels")
    reason = registry.capabilities(lacking).unsupported_reason("uniform", 1, None, channels=True)
    assert reason is not None and not chooser.is_enabled(lacking) and chooser.tooltip(lacking) == reason


def test_selecting_a_channel_has_the_editor_edit_its_tf_and_show_its_histogram(shown, qtbot):
    window, before = shown
    state, panel, editor = window.state, window.docks.channels, window.docks.tf_panel.editor_1d
    stack = window.docks.history.stack
    steps = stack.count()
    panel.table.setCurrentCell(1, NAME)
    ctf = state.channel_transfer_function
    assert state.selected_channel == 1 and editor.transfer_function() is ctf.tfs[1]
    assert stack.count() == steps  # a selection is not an edit
    data = editor.data_volume()
    assert np.shares_memory(data.values, state.channels.values[1])
    np.testing.assert_array_equal(editor.curve.histogram.counts, value_histogram(data).counts)
    frame = _frame_after(window, qtbot, lambda: editor.unit_spin.setValue(4.0))
    assert ctf.tfs[1].opacity_unit_distance == pytest.approx(4.0) and ctf.tfs[0].opacity_unit_distance == 1.0
    _assert_drawn(frame, _expected(window, frame, ctf.copy()))
    left, right = _halves(frame)
    assert np.abs(frame.rgb[:, left].astype(np.int16) - before.rgb[:, left]).max() <= 1  # channel A as it was
    assert not np.array_equal(frame.rgb[:, right], before.rgb[:, right])
    frame = _frame_after(window, qtbot, window.docks.undo_action.trigger)
    assert state.channel_transfer_function.tfs[1].opacity_unit_distance == 1.0
    assert state.transfer_function is state.channel_transfer_function.tfs[1]  # still channel B's
    _assert_drawn(frame, before.rgb)


def test_visibility_weight_and_colour_edits_draw_at_once_and_undo_one_step_each(shown, qtbot, monkeypatch):
    window, before = shown
    state, panel = window.state, window.docks.channels
    stack, undo = window.docks.history.stack, window.docks.undo_action
    steps = stack.count()
    background = to_png_pixels(np.zeros((1, 1, 4), np.float32), state.background)[0, 0]
    left, right = _halves(before)

    hidden = _frame_after(window, qtbot, lambda: panel.show_box(0).setChecked(False))
    assert state.channel_transfer_function.visible == [False, True, False]
    assert np.all(hidden.rgb[:, left] == background)
    _assert_drawn(hidden, _expected(window, hidden, state.channel_transfer_function.copy()))

    heavier = _frame_after(window, qtbot, lambda: panel.weight_box(1).setValue(3.0))
    assert state.channel_transfer_function.weights[1] == 3.0
    _assert_drawn(heavier, _expected(window, heavier, state.channel_transfer_function.copy()))
    assert not np.array_equal(heavier.rgb[:, right], hidden.rgb[:, right])

    monkeypatch.setattr(panel, "choose_color", lambda initial: QColor(0, 0, 255))
    blue = _frame_after(window, qtbot, lambda: panel.pick_color(1))
    assert channel_color(state.channel_transfer_function.tfs[1]) == (0.0, 0.0, 1.0)
    assert state.transfer_function is state.channel_transfer_function.tfs[0]  # channel A still edited
    row = blue.rgb[blue.height // 2][right]
    assert np.all(row[:, 2] > row[:, 1])
    _assert_drawn(blue, _expected(window, blue, state.channel_transfer_function.copy()))

    assert stack.count() == steps + 3 and undo.text() == "&Undo edit channels"
    frame = _frame_after(window, qtbot, undo.trigger)
    _assert_drawn(frame, heavier.rgb)
    frame = _frame_after(window, qtbot, undo.trigger)
    assert panel.weight_box(1).value() == 1.0
    _assert_drawn(frame, hidden.rgb)
    frame = _frame_after(window, qtbot, undo.trigger)
    assert panel.show_box(0).isChecked()
    _assert_drawn(frame, before.rgb)
    frame = _frame_after(window, qtbot, window.docks.redo_action.trigger)
    assert not panel.show_box(0).isChecked()
    _assert_drawn(frame, hidden.rgb)


def test_a_volume_with_channels_takes_no_labels(shown):
    window, _ = shown
    assert not window.labels.open_action.isEnabled()


def test_a_scene_keeps_the_channels_and_their_tfs(shown, qtbot, tmp_path, error_boxes):
    window, _ = shown
    panel = window.docks.channels
    _frame_after(window, qtbot, lambda: panel.weight_box(1).setValue(2.5))
    before = window.state.channel_transfer_function.to_dict()
    scene = tmp_path / "cells.json"
    assert window.scenes.save(scene)
    data = json.loads(scene.read_text())
    assert data["volume"]["channels"] is True and data["transfer_function"]["kind"] == "channels"
    window.state.load(
        window.state.volume, window.state.transfer_function, window.state.camera
    )  # defaults again
    assert window.state.channel_transfer_function.to_dict() != before
    with qtbot.waitSignal(window.files.loadFinished, timeout=FRAME_TIMEOUT_MS):
        window.files.open_input(scene)
    qtbot.waitUntil(
        lambda: window.state.channel_transfer_function.to_dict() == before, timeout=FRAME_TIMEOUT_MS
    )
    assert error_boxes == [] and panel.weight_box(1).value() == 2.5 and panel.name(0) == "A"
