"""Label volumes in the app (Real-Time Volume Graphics, chapter 16): File > Open Labels, the Labels
panel, and the frames drawn with a TF per label.

The scene: a 24^3 grid whose central box has the value 1 (0 around it), split into label 1 (x < 12)
and label 2 (x >= 12) over the whole grid, seen along -z with a parallel camera, so the left half
of the image shows label 1 and the right half label 2. The oracle of a frame is the raycast
renderer itself, given the TF per label the test expects, at the frame's own settings and camera,
converted to pixels as the render service converts them; and where only a hidden label lies on
the rays, the frame is the background.
"""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
from PyQt5.QtGui import QColor

from tests.app.conftest import FRAME_TIMEOUT_MS
from tests.app.renderer_picks import renderer_without
from volren import io
from volren.app.core.loading import LoadedInput
from volren.app.core.tf_seeding import seeded_2d
from volren.app.rendering.render_service import tf_key
from volren.app.window.label_actions import sidecar_path
from volren.io.image_io import to_png_pixels
from volren.model.camera import Camera
from volren.model.labels import LabelMap, LabelStyle, LabelTransferFunction
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import UniformVolume
from volren.renderers.base import render_frame
from volren.renderers.registry import registry

N = 24
#: The first raycast frame of a process may compile its kernels (numba; minutes on a busy 2-core machine).
FIRST_FRAME_TIMEOUT_MS = 180_000
SPLIT = 12  # label 1 below x = SPLIT, label 2 from it


def _values() -> np.ndarray:
    values = np.zeros((N, N, N), np.float32)
    values[3:-3, 3:-3, 3:-3] = 1.0
    return values


def _labels() -> np.ndarray:
    labels = np.ones((N, N, N), np.uint8)
    labels[:, :, SPLIT:] = 2
    return labels


def _tf() -> TransferFunction1D:
    return TransferFunction1D(np.array([[0.0, 1, 1, 1], [1.0, 1, 1, 1]]), np.array([[0.0, 0.0], [1.0, 0.5]]))


@pytest.fixture
def files(tmp_path):
    """(volume file, label file with its sidecar of names and one colour)."""
    volume_path, label_path = tmp_path / "head.vti", tmp_path / "seg.vti"
    io.save_volume(UniformVolume(_values(), name="head"), volume_path)
    io.save_volume(UniformVolume(_labels(), name="seg"), label_path)
    info = {"labels": [{"value": 1, "name": "left"}, {"value": 2, "name": "right", "color": [0.0, 1.0, 0.0]}]}
    (tmp_path / "seg.labels.json").write_text(json.dumps(info))
    return volume_path, label_path


def _current(window):
    """A fullFrameShown check: the frame draws what the state holds now."""

    def check(frame) -> bool:
        tf = window.state.drawn_transfer_function
        return frame.tf_key == tf_key(tf) and frame.renderer == window.state.renderer

    return check


def _frame_after(window, qtbot, action, timeout_ms: int = FRAME_TIMEOUT_MS):
    with qtbot.waitSignal(window.fullFrameShown, timeout=timeout_ms, check_params_cb=_current(window)) as got:
        action()
    return got.args[0]


@pytest.fixture
def labelled(make_window, qtbot, files, error_boxes):
    """A window showing the volume with raycast along -z (parallel), its labels opened."""
    volume_path, label_path = files
    window = make_window()
    window.resize(700, 360)  # a small viewport: fast frames
    volume = io.load_volume(volume_path)
    loaded = LoadedInput(volume, _tf(), source="head", volume_path=str(volume_path))
    _frame_after(window, qtbot, lambda: window.files.apply_loaded(loaded, "raycast"), FIRST_FRAME_TIMEOUT_MS)
    camera = Camera.orbit(volume.bounds, 0.0, 0.0, 1.0, True, window.viewport.aspect())
    _frame_after(window, qtbot, lambda: window.state.set_camera(camera))
    frame = _frame_after(window, qtbot, lambda: window.labels.open_labels(label_path))
    assert window.state.labels is not None and error_boxes == []
    return window, frame


def _expected(window, frame, label_tf: LabelTransferFunction) -> np.ndarray:
    """The frame raycast draws of the state's volume with `label_tf`, at `frame`'s settings and
    camera, as the render service turns it into pixels."""
    with registry.create(frame.renderer) as renderer:
        renderer.set_settings(frame.settings)
        renderer.set_volume(window.state.volume)
        renderer.set_transfer_function(label_tf)
        image, _ = render_frame(renderer, frame.camera, frame.width, frame.height)
    return to_png_pixels(image, window.state.background)


def _halves(frame) -> tuple[np.ndarray, np.ndarray]:
    """Pixel columns through the box of value 1 that see only label 1 (left of the image) and only
    label 2 (right), with a margin of two voxels' width around the split and the box's sides."""
    x = (np.arange(frame.width) + 0.5) / frame.width  # parallel view: the bounds fill part of it
    camera = frame.camera
    half_width = camera.parallel_scale * frame.width / frame.height
    world_x = camera.focal_point[0] + (2 * x - 1) * half_width
    return (world_x > 5) & (world_x < SPLIT - 2.5), (world_x > SPLIT + 1.5) & (world_x < N - 6)


def _background(window) -> np.ndarray:
    return to_png_pixels(np.zeros((1, 1, 4), np.float32), window.state.background)[0, 0]


def test_open_labels_lists_them_by_name_and_draws_by_label(labelled):
    window, frame = labelled
    panel = window.docks.labels
    assert panel.labels == (1, 2)
    names = [panel.table.item(row, 2).text() for row in range(panel.table.rowCount())]
    assert names == ["left", "right"]
    label_tf = window.state.label_transfer_function
    assert label_tf.base is window.state.transfer_function  # the 1D editor's TF itself
    assert label_tf.style(2).color == (0.0, 1.0, 0.0)  # the sidecar's colour
    assert frame.settings.preintegration is False  # raycast pre-integrates no labels
    np.testing.assert_array_equal(frame.rgb, _expected(window, frame, label_tf))
    left, right = _halves(frame)
    row = frame.rgb[frame.height // 2]
    assert np.all(row[right][:, 1] > row[right][:, 0])  # label 2 in green


def test_unticking_a_label_hides_it(labelled, qtbot):
    window, before = labelled
    panel = window.docks.labels
    frame = _frame_after(window, qtbot, lambda: panel.show_box(2).setChecked(False))
    assert window.state.label_transfer_function.style(2).visible is False
    expected = window.state.label_transfer_function.copy()
    np.testing.assert_array_equal(frame.rgb, _expected(window, frame, expected))
    left, right = _halves(frame)
    background = _background(window)
    assert np.all(frame.rgb[:, right] == background)  # only label 2 there: nothing drawn
    assert not np.all(before.rgb[:, right] == background)
    np.testing.assert_array_equal(frame.rgb[:, left], before.rgb[:, left])


def test_solo_shows_one_label_and_gives_the_others_back(labelled, qtbot):
    window, before = labelled
    panel = window.docks.labels
    frame = _frame_after(window, qtbot, lambda: panel.solo_box(2).setChecked(True))
    left, right = _halves(frame)
    assert np.all(frame.rgb[:, left] == _background(window))
    assert not panel.show_box(1).isChecked() and panel.show_box(2).isChecked()
    frame = _frame_after(window, qtbot, lambda: panel.solo_box(2).setChecked(False))
    assert panel.show_box(1).isChecked() and panel.show_box(2).isChecked()
    np.testing.assert_array_equal(frame.rgb, before.rgb)


def test_solo_restores_the_visibility_from_before(labelled, qtbot):
    window, _ = labelled
    panel = window.docks.labels
    _frame_after(window, qtbot, lambda: panel.show_box(2).setChecked(False))
    _frame_after(window, qtbot, lambda: panel.solo_box(2).setChecked(True))
    _frame_after(window, qtbot, lambda: panel.solo_box(2).setChecked(False))
    label_tf = window.state.label_transfer_function
    assert (label_tf.style(1).visible, label_tf.style(2).visible) == (True, False)


def test_colour_and_opacity_edits_reach_the_frame(labelled, qtbot, monkeypatch):
    window, _ = labelled
    panel = window.docks.labels
    monkeypatch.setattr(panel, "choose_color", lambda initial: QColor(255, 0, 0))
    frame = _frame_after(window, qtbot, lambda: panel.pick_color(1))
    label_tf = window.state.label_transfer_function
    assert label_tf.style(1).color == (1.0, 0.0, 0.0)
    expected = LabelTransferFunction(
        _tf(), {1: LabelStyle(color=(1.0, 0.0, 0.0)), 2: LabelStyle(color=(0, 1, 0))}
    )
    np.testing.assert_array_equal(frame.rgb, _expected(window, frame, expected))
    left, _ = _halves(frame)
    row = frame.rgb[frame.height // 2][left]
    assert np.all(row[:, 0] >= row[:, 1])  # red where label 1 is drawn
    frame = _frame_after(window, qtbot, lambda: panel.opacity_box(1).setValue(0.0))
    assert label_tf.style(1).opacity == 0.0
    assert np.all(frame.rgb[:, left] == _background(window))


def test_an_edit_of_the_1d_tf_reaches_every_label_drawn_with_it(labelled, qtbot):
    window, before = labelled
    editor = window.docks.tf_panel.editor_1d
    frame = _frame_after(window, qtbot, lambda: editor.unit_spin.setValue(8.0))
    assert window.state.label_transfer_function.base.opacity_unit_distance == pytest.approx(8.0)
    edited = _tf()
    edited.set_opacity_unit_distance(8.0)
    expected = LabelTransferFunction.for_labels(edited, window.state.labels)
    expected.set_style(2, LabelStyle(color=(0.0, 1.0, 0.0)))
    np.testing.assert_array_equal(frame.rgb, _expected(window, frame, expected))
    assert not np.array_equal(frame.rgb, before.rgb)


def test_the_renderer_box_refuses_renderers_without_labels(labelled):
    window, _ = labelled
    chooser = window.renderers.chooser
    assert chooser.is_enabled("raycast") and window.state.renderer == "raycast"
    lacking = renderer_without("labels")
    reason = registry.capabilities(lacking).unsupported_reason("uniform", 1, None, labels=True)
    assert reason is not None and not chooser.is_enabled(lacking)
    assert chooser.tooltip(lacking) == reason


def test_opening_labels_moves_off_a_renderer_that_cannot_draw_them(make_window, qtbot, files, error_boxes):
    volume_path, label_path = files
    window = make_window()
    window.resize(700, 360)
    assert not window.labels.open_action.isEnabled()  # no volume to label yet
    loaded = LoadedInput(io.load_volume(volume_path), _tf(), source="head", volume_path=str(volume_path))
    lacking = renderer_without("labels")
    _frame_after(window, qtbot, lambda: window.files.apply_loaded(loaded, lacking))
    assert window.labels.open_action.isEnabled() and not window.labels.close_action.isEnabled()
    _frame_after(window, qtbot, lambda: window.labels.open_labels(label_path), FIRST_FRAME_TIMEOUT_MS)
    assert window.state.renderer != lacking and error_boxes == []
    assert registry.capabilities(window.state.renderer).kinds["uniform"].labels


def test_closing_labels_gives_the_plain_frame_back(labelled, qtbot):
    window, _ = labelled
    assert window.labels.close_action.isEnabled()
    frame = _frame_after(window, qtbot, window.labels.close_action.trigger)
    assert (
        window.state.labels is None and window.state.drawn_transfer_function is window.state.transfer_function
    )
    assert window.docks.labels.labels == ()
    assert not window.labels.close_action.isEnabled()
    np.testing.assert_array_equal(frame.rgb, _expected(window, frame, window.state.transfer_function))


def test_a_label_file_off_the_grid_is_one_line_error(labelled, qtbot, tmp_path, error_boxes):
    window, _ = labelled
    path = tmp_path / "small.vti"
    io.save_volume(UniformVolume(np.ones((4, 4, 4), np.uint8)), path)
    with qtbot.waitSignal(window.labels.loader.failed, timeout=FRAME_TIMEOUT_MS):
        window.labels.open_labels(path)
    assert len(error_boxes) == 1 and "\n" not in error_boxes[0][1] and "small.vti" in error_boxes[0][1]
    assert window.state.labels is not None  # what was shown stays


def test_a_2d_tf_draws_no_labels_and_the_panel_says_so(labelled):
    window, _ = labelled
    state = window.state
    label_map = state.labels
    state.set_transfer_function(seeded_2d(state.transfer_function, state.volume.value_range, 1.0))
    assert state.label_transfer_function is not None and not state.labels_drawn
    assert state.drawn_transfer_function is state.transfer_function
    assert "2D" in window.docks.labels.note.text() and not window.docks.labels.note.isHidden()
    one_d = _tf()
    state.set_transfer_function(one_d)
    assert state.labels_drawn and state.label_transfer_function.base is one_d and state.labels is label_map
    assert window.docks.labels.note.isHidden()


def test_state_crop_cuts_the_labels_too():
    from volren.app.core.state import ViewState, default_camera

    state = ViewState(
        renderer="fake_no_clip"
    )  # not a registered renderer: it clips nothing, the cut is drawn
    volume = UniformVolume(_values(), labels=LabelMap(_labels()))
    state.load(volume, _tf(), default_camera(volume))
    state.set_crop((0.0, 8.0, 0.0, 23.0, 0.0, 23.0))
    shown = state.render_volume
    assert shown.labels is not None and shown.labels.values.shape == shown.values.shape
    assert shown.labels.present == (1,)
    assert replace(volume, labels=None).labels is None


def test_a_scene_keeps_the_labels_and_their_styles(labelled, qtbot, tmp_path, error_boxes):
    window, _ = labelled
    panel = window.docks.labels
    _frame_after(window, qtbot, lambda: panel.show_box(2).setChecked(False))
    _frame_after(window, qtbot, lambda: panel.opacity_box(1).setValue(2.0))
    before = window.state.label_transfer_function.to_dict()
    scene = tmp_path / "scenes" / "labelled.json"
    scene.parent.mkdir()
    assert window.scenes.save(scene)
    data = json.loads(scene.read_text())
    assert data["volume"]["labels"] == "../seg.vti" and data["transfer_function"]["kind"] == "labels"
    _frame_after(window, qtbot, window.labels.close_labels)
    with qtbot.waitSignal(window.files.loadFinished, timeout=FRAME_TIMEOUT_MS):
        window.files.open_input(scene)
    qtbot.waitUntil(lambda: window.state.labels is not None, timeout=FRAME_TIMEOUT_MS)
    state = window.state
    assert error_boxes == [] and state.labels.present == (1, 2)
    assert state.label_transfer_function.to_dict() == before
    assert state.label_transfer_function.base is state.transfer_function
    assert state.labels_path == str(tmp_path / "seg.vti")
    assert (
        panel.labels == (1, 2) and not panel.show_box(2).isChecked() and panel.opacity_box(1).value() == 2.0
    )
    # another volume drops the labels
    loaded = LoadedInput(UniformVolume(_values()), _tf(), source="plain")
    _frame_after(window, qtbot, lambda: window.files.apply_loaded(loaded))
    assert state.labels is None and state.labels_path is None and panel.labels == ()


def test_label_edits_undo_and_redo_one_step_each(labelled, qtbot):
    window, before = labelled
    panel, undo = window.docks.labels, window.docks.undo_action
    stack = window.docks.history.stack
    steps = stack.count()
    hidden = _frame_after(window, qtbot, lambda: panel.show_box(2).setChecked(False))
    _frame_after(window, qtbot, lambda: panel.opacity_box(1).setValue(3.0))
    assert stack.count() == steps + 2 and undo.text() == "&Undo edit labels"
    _frame_after(window, qtbot, undo.trigger)
    assert (
        window.state.label_transfer_function.style(1).opacity == 1.0 and panel.opacity_box(1).value() == 1.0
    )
    frame = _frame_after(window, qtbot, undo.trigger)
    assert window.state.label_transfer_function.style(2).visible and panel.show_box(2).isChecked()
    assert window.state.label_transfer_function.base is window.state.transfer_function
    np.testing.assert_array_equal(frame.rgb, before.rgb)
    frame = _frame_after(window, qtbot, window.docks.redo_action.trigger)
    np.testing.assert_array_equal(frame.rgb, hidden.rgb)
    assert not window.state.label_transfer_function.style(2).visible


def test_a_screenshot_draws_the_labels_as_the_view_does(labelled, qtbot, tmp_path):
    from volren.app.files.screenshot import ScreenshotJob, render_job

    window, _ = labelled
    frame = _frame_after(window, qtbot, lambda: window.docks.labels.show_box(1).setChecked(False))
    job = ScreenshotJob.of_view(window.state, tmp_path / "shot.png", frame.width, frame.height)
    assert isinstance(job.tf, LabelTransferFunction) and job.volume.labels is not None
    shot = to_png_pixels(render_job(job), window.state.background)
    np.testing.assert_array_equal(shot, frame.rgb)


def test_pre_integration_is_off_for_labels_and_the_status_bar_says_so(labelled, qtbot, error_boxes):
    window, _ = labelled
    state = window.state
    frame = _frame_after(window, qtbot, lambda: state.set_settings(state.settings.with_(preintegration=True)))
    assert state.settings.preintegration and not frame.settings.preintegration
    assert frame.settings == state.settings.with_(preintegration=False) and error_boxes == []
    assert state.renderer == "raycast"  # kept: it draws labels, without pre-integration
    assert "labels without pre-integration" in window.renderers.frame_label.text()
    np.testing.assert_array_equal(frame.rgb, _expected(window, frame, state.label_transfer_function))
    frame = _frame_after(window, qtbot, window.labels.close_labels)
    assert frame.settings.preintegration and "pre-integration" not in window.renderers.frame_label.text()


@pytest.mark.parametrize(
    ("name", "sidecar"),
    [
        ("seg.seg.nrrd", "seg.labels.json"),
        ("seg.nii.gz", "seg.labels.json"),
        ("pd25_subcortical.vti", "pd25_subcortical.labels.json"),
    ],
)
def test_the_sidecar_is_named_after_the_label_file(tmp_path, name, sidecar):
    assert sidecar_path(tmp_path / name) == tmp_path / sidecar
