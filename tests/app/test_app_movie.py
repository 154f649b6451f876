"""File > Export Movie: an orbit of the view recorded off the GUI thread, with progress and cancel."""

from __future__ import annotations

import threading
import time
from typing import ClassVar

import numpy as np
import pytest
from PyQt5.QtWidgets import QDialog, QDialogButtonBox, QMessageBox, QPushButton

from tests.app.test_app_files import TIMEOUT_MS, good_volume, show
from volren.app.files import movie_dialog
from volren.io.image_io import to_png_pixels
from volren.model.animation import Animation
from volren.renderers.registry import registry

imageio = pytest.importorskip("imageio.v2", reason="volren[movie] is part of the test set-up")


@pytest.fixture
def camera_colored(fake_renderers):
    """A renderer whose colour is its camera's direction: every orbit frame differs, exactly."""

    class CameraColored(fake_renderers["fake"]):
        name: ClassVar[str] = "fake_camera"
        delay_s: ClassVar[float] = 0.0
        threads: ClassVar[list[threading.Thread]] = []

        def _render(self, camera, width, height, progress):
            type(self).threads.append(threading.current_thread())
            time.sleep(self.delay_s)
            if progress is not None:
                progress(0.5)
            image = np.zeros((height, width, 4), np.float32)
            image[..., :3] = 0.5 + 0.5 * np.asarray(camera.direction, np.float32)
            image[..., 3] = 1.0
            image[: height // 2, : width // 3] *= 0.5  # and where the top is
            return image, {}

    registry.register(CameraColored.name, CameraColored, replace=True)
    try:
        yield CameraColored
    finally:
        registry.unregister(CameraColored.name)


@pytest.fixture
def movie_window(make_window, ini, qtbot, camera_colored):
    w = make_window(settings=ini)
    show(w, qtbot, good_volume(), renderer="fake_camera")
    return w


def decoded(path) -> list[np.ndarray]:
    return [np.asarray(frame)[..., :3] for frame in imageio.mimread(path, memtest=False)]


def test_export_records_the_orbit_of_the_view_in_its_own_thread(movie_window, camera_colored, qtbot, tmp_path,
                                                                error_boxes):  # fmt: skip
    w = movie_window
    path = tmp_path / "orbit.mp4"
    animation = Animation(frames=4, fps=8, orbit_degrees=360)
    camera_colored.threads.clear()
    with qtbot.waitSignal(w.movies.saved, timeout=TIMEOUT_MS) as saved:
        assert w.movies.export(path, 30, 20, animation, lossless=True)
    assert saved.args == [str(path)]
    assert threading.main_thread() not in camera_colored.threads
    frames = decoded(path)
    assert len(frames) == 4
    volume, camera = w.state.render_volume, w.state.camera
    with registry.create("fake_camera") as direct:
        direct.set_volume(volume)
        direct.set_transfer_function(w.state.transfer_function)
        for index, frame in enumerate(frames):
            expected = direct.render(animation.camera(index, camera, volume.bounds, 30 / 20), 30, 20)
            np.testing.assert_array_equal(
                frame, to_png_pixels(expected, w.state.background), err_msg=str(index)
            )
    assert not np.array_equal(frames[0], frames[1])
    assert error_boxes == [] and "Saved" in w.statusBar().currentMessage()


def test_progress_counts_frames_and_cancel_leaves_no_file(movie_window, camera_colored, qtbot, tmp_path):
    w = movie_window
    camera_colored.delay_s = 0.25
    path = tmp_path / "cancelled.gif"
    assert w.movies.export(path, 16, 16, Animation(frames=40))
    dialog = w.movies._progress.dialog
    qtbot.waitUntil(lambda: dialog.isVisible() and "frame 3 of 40" in dialog.labelText(), timeout=TIMEOUT_MS)
    assert 0 < dialog.value() < 10
    (cancel,) = [b for b in dialog.findChildren(QPushButton) if b.text() == "Cancel"]
    with qtbot.waitSignal(w.movies.exporter.busyChanged, timeout=2000):
        cancel.click()
    assert w.movies._progress is None
    assert w.movies.exporter.shutdown(TIMEOUT_MS)
    assert list(tmp_path.iterdir()) == []


def test_bad_requests_are_reported_in_one_line(movie_window, make_window, ini, qtbot, tmp_path, error_boxes):
    assert not movie_window.movies.export(tmp_path / "movie.avi", 16, 16, Animation(frames=2))
    assert "a movie is written as .mp4 or .gif" in error_boxes[-1][1]
    assert not movie_window.movies.export(tmp_path / "no" / "movie.mp4", 16, 16, Animation(frames=2))
    assert "does not exist" in error_boxes[-1][1]
    empty = make_window(settings=ini)
    assert not empty.movies.export(tmp_path / "movie.mp4", 16, 16, Animation(frames=2))
    assert "open a volume first" in error_boxes[-1][1]
    assert all(title == "Cannot export the movie" and "\n" not in text for title, text in error_boxes)
    assert list(tmp_path.iterdir()) == []


def test_the_menu_action_uses_the_dialog_choice(movie_window, qtbot, tmp_path, monkeypatch):
    w = movie_window
    asked = []

    def ask(parent, path, fields):
        asked.append((path, (fields.width, fields.height)))
        if len(asked) > 1:
            return None  # cancelled: nothing starts
        return movie_dialog.MovieChoice(str(tmp_path / "menu.gif"), 24, 18, Animation(frames=3, fps=5))

    monkeypatch.setattr(movie_dialog, "ask_movie", ask)
    assert w.movies.action in w.menuBar().actions()[0].menu().actions()
    with qtbot.waitSignal(w.movies.saved, timeout=TIMEOUT_MS):
        w.movies.action.trigger()
    assert asked[0][1] == w.viewport.pixel_size() and asked[0][0].endswith("volren.mp4")
    frames = decoded(tmp_path / "menu.gif")
    assert len(frames) == 3 and frames[0].shape == (18, 24, 3)
    w.movies.action.trigger()
    assert asked[1][0] == str(tmp_path / "menu.gif")  # the dialog offers the last movie again
    assert not w.movies.exporter.busy


def test_the_dialog_fields_make_the_choice(qtbot, tmp_path):
    dialog = movie_dialog.MovieDialog(None, str(tmp_path / "film"), movie_dialog.MovieFields(320, 200))
    qtbot.addWidget(dialog)
    assert (dialog.width_box.value(), dialog.height_box.value()) == (320, 200)
    dialog.frames_box.setValue(90)
    dialog.fps_box.setValue(15)
    dialog.orbit_box.setValue(180)
    assert dialog.length_label.text() == "6.0 s"
    assert dialog.lossless.isEnabled()  # no suffix: an MP4
    dialog.lossless.setChecked(True)
    choice = dialog.choice()
    assert choice.path == str(tmp_path / "film.mp4") and choice.lossless
    assert (choice.animation.frames, choice.animation.fps, choice.animation.orbit_degrees) == (
        90,
        15.0,
        180.0,
    )
    dialog.path_edit.setText(str(tmp_path / "film.gif"))
    assert not dialog.lossless.isEnabled() and not dialog.choice().lossless
    dialog.path_edit.setText("  ")
    assert not dialog.buttons.button(QDialogButtonBox.Save).isEnabled()


def test_the_dialog_offers_the_last_movies_fields_again_now_and_in_a_later_session(movie_window, make_window, ini,
                                                                                  qtbot, tmp_path, monkeypatch):  # fmt: skip
    """The real dialog (only its modal loop replaced): the first time the viewport's size and the
    defaults; after a movie, that movie's fields, in this window and in a new one (the settings)."""
    shown, answers = [], []

    def exec_(dialog):
        shown.append((dialog.width_box.value(), dialog.height_box.value(), dialog.frames_box.value(),
                      dialog.fps_box.value(), dialog.orbit_box.value(), dialog.lossless.isChecked()))  # fmt: skip
        return answers.pop(0)(dialog)

    def make_a_movie(dialog):
        dialog.path_edit.setText(str(tmp_path / "first.mp4"))
        for box, value in ((dialog.width_box, 24), (dialog.height_box, 18), (dialog.frames_box, 3),
                           (dialog.fps_box, 5.0), (dialog.orbit_box, 90.0)):  # fmt: skip
            box.setValue(value)
        dialog.lossless.setChecked(True)
        return QDialog.Accepted

    monkeypatch.setattr(movie_dialog.MovieDialog, "exec_", exec_)
    answers.append(make_a_movie)
    with qtbot.waitSignal(movie_window.movies.saved, timeout=TIMEOUT_MS):
        movie_window.movies.action.trigger()
    assert shown[0] == (*movie_window.viewport.pixel_size(), 120, 30.0, 360.0, False)
    answers.append(lambda dialog: QDialog.Rejected)
    movie_window.movies.action.trigger()
    later = make_window(settings=ini)
    show(later, qtbot, good_volume(), renderer="fake_camera")
    answers.append(lambda dialog: QDialog.Rejected)
    later.movies.action.trigger()
    assert shown[1] == shown[2] == (24, 18, 3, 5.0, 90.0, True) and not later.movies.exporter.busy


@pytest.mark.parametrize("stored", [None, "", "not json", "[]", '{"width": 24}', '{"width": 24, "height": "18"}',
                                    '{"width": 24, "height": 18, "fps": NaN}', '{"width": 24, "height": 18, "x": 1}',
                                    '{"width": true, "height": 18}', '{"width": 24, "height": 18, "lossless": 1}'])  # fmt: skip
def test_stored_movie_fields_that_do_not_fit_give_the_defaults(stored):
    assert movie_dialog.MovieFields.from_json(stored) is None
    fields = movie_dialog.MovieFields(24, 18, 3, 5.0, -90.0, True)
    assert movie_dialog.MovieFields.from_json(fields.to_json()) == fields


@pytest.mark.parametrize("answer, closes", [(QMessageBox.No, False), (QMessageBox.Yes, True)])
def test_closing_while_recording_asks_first(movie_window, camera_colored, qtbot, tmp_path, monkeypatch, answer,
                                            closes):  # fmt: skip
    w = movie_window
    camera_colored.delay_s = 0.2
    asked = []
    monkeypatch.setattr(QMessageBox, "question", lambda *args, **kwargs: asked.append(args[2]) or answer)
    assert w.movies.export(tmp_path / "long.mp4", 16, 16, Animation(frames=50))
    w.close()
    assert asked and "movie is still being rendered" in asked[0]
    assert w.isVisible() != closes and w.movies.exporter.busy != closes
    w.movies.exporter.cancel()
    assert w.movies.exporter.shutdown(TIMEOUT_MS)
    assert not (tmp_path / "long.mp4").exists()
