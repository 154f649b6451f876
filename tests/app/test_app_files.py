"""The File menu of the app: recent files, cancelling loads, scenes and screenshots (pytest-qt, offscreen).

Every window here keeps its recent files in a temporary INI file, never in the person's own
settings; renderers are the constant-colour fakes of conftest, so pixels have exact oracles.
"""

from __future__ import annotations

import threading
from pathlib import Path
from typing import ClassVar

import numpy as np
import pytest
from PyQt5.QtCore import QSettings, Qt
from PyQt5.QtGui import QKeySequence

from volren.app.core.loading import LoadCancelled, LoadedInput, load_input, view_scene
from volren.app.files import screenshot_dialog
from volren.app.files.recent_files import RecentFiles, RecentFilesMenu
from volren.errors import VolrenError
from volren.io.image_io import to_png_pixels
from volren.model import TFWidget, TransferFunction2D
from volren.model.camera import Camera
from volren.model.settings import RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.renderers.registry import registry
from volren.samples import marschner_lobb, sample_paths, sample_transfer_functions

pytestmark = pytest.mark.qt

TIMEOUT_MS = 20000


@pytest.fixture
def fakes(fake_renderers, fake_2d):
    """conftest's fake renderers and `fake_2d`, the constant-colour one drawing 2D TFs too."""
    return fake_renderers


@pytest.fixture
def files_window(make_window, ini):
    """make_window with the isolated settings."""
    return lambda **kwargs: make_window(settings=ini, **kwargs)


def good_volume(n: int = 9) -> LoadedInput:
    return LoadedInput(marschner_lobb(n), sample_transfer_functions()["marschner_lobb"], source=f"ml{n}")


class ScriptedLoad:
    """An injected load function: '*slow*' files block until released, '*bad*' ones fail,
    anything else loads a small volume named after the file's stem length."""

    def __init__(self) -> None:
        self.started = threading.Event()
        self.release = threading.Event()
        self.finished = threading.Event()

    def __call__(self, path, tf, scalars) -> LoadedInput:
        name = Path(path).name
        if "slow" in name:
            self.started.set()
            try:
                assert self.release.wait(15), "the test never released the slow load"
                return LoadedInput(marschner_lobb(7), TransferFunction1D.ramp(0, 1), source=name)
            finally:
                self.finished.set()
        if "bad" in name:
            raise VolrenError(f"{path}: not a volume")
        return LoadedInput(marschner_lobb(11), sample_transfer_functions()["marschner_lobb"], source=name)


def png_pixels(path: Path) -> np.ndarray:
    """(H, W, 3) uint8 of a PNG file."""
    from PIL import Image

    with Image.open(path) as image:
        assert image.format == "PNG"
        return np.asarray(image.convert("RGB"))


def show(window, qtbot, loaded: LoadedInput, renderer: str = "fake") -> None:
    with qtbot.waitSignal(window.fullFrameShown, timeout=TIMEOUT_MS):
        window.files.apply_loaded(loaded, renderer)


# ---------------------------------------------------------------------------- recent files
def test_recent_files_order_dedup_limit_and_persistence(ini, tmp_path, monkeypatch):
    recent = RecentFiles(ini, limit=3)
    seen = []
    recent.changed.connect(lambda: seen.append(recent.paths()))
    a, b, c, d = (str(tmp_path / f"{n}.vti") for n in "abcd")
    recent.add(a)
    assert recent.paths() == [a]
    assert RecentFiles(QSettings(ini.fileName(), QSettings.IniFormat)).paths() == [
        a
    ]  # one entry survives INI
    recent.add(b)
    recent.add(a)  # again: moves to the top, not listed twice
    assert recent.paths() == [a, b]
    recent.add(c)
    recent.add(d)
    assert recent.paths() == [d, c, a]  # at most `limit`, the oldest dropped
    monkeypatch.chdir(tmp_path)
    recent.add("b.vti")  # stored absolute
    assert recent.paths() == [b, d, c]
    reopened = RecentFiles(QSettings(ini.fileName(), QSettings.IniFormat), limit=3)
    assert reopened.paths() == [b, d, c]
    recent.remove(d)
    assert recent.paths() == [b, c]
    recent.clear()
    assert recent.paths() == [] and RecentFiles(QSettings(ini.fileName(), QSettings.IniFormat)).paths() == []
    assert len(seen) == 8 and seen[-1] == []


def test_recent_menu_greys_missing_files_and_clears(qtbot, ini, tmp_path):
    recent = RecentFiles(ini)
    here, gone = tmp_path / "here.vti", tmp_path / "gone.vti"
    here.write_text("x")
    recent.add(gone)
    recent.add(here)
    menu = RecentFilesMenu(recent)
    qtbot.addWidget(menu)
    entries = menu.entries()
    assert [e.data() for e in entries] == [str(here), str(gone)]
    assert "here.vti" in entries[0].text() and entries[0].isEnabled()
    assert "gone.vti" in entries[1].text() and not entries[1].isEnabled()
    assert "missing" in entries[1].toolTip()
    with qtbot.waitSignal(menu.fileChosen) as chosen:
        entries[0].trigger()
    assert chosen.args == [str(here)]
    here.unlink()
    menu.aboutToShow.emit()  # opening the menu looks again
    assert not any(e.isEnabled() for e in menu.entries())
    assert menu.clear_action.isEnabled()
    menu.clear_action.trigger()
    assert recent.paths() == [] and menu.entries() == [] and not menu.clear_action.isEnabled()
    assert any(a.text() == "No recent files" and not a.isEnabled() for a in menu.actions())


def test_opened_files_go_to_the_recent_menu_and_open_from_it(
    files_window, fakes, qtbot, tmp_path, error_boxes
):
    w = files_window(load=ScriptedLoad())
    first, second, bad = tmp_path / "first.vti", tmp_path / "second.vti", tmp_path / "bad.vti"
    for p in (first, second, bad):
        p.write_text("x")
    for p in (first, second):
        with qtbot.waitSignal(w.fullFrameShown, timeout=TIMEOUT_MS):
            w.files.open_input(p, renderer="fake")
    with qtbot.waitSignal(w.files.loadFinished, timeout=TIMEOUT_MS) as failed:
        w.files.open_input(bad)
    assert failed.args == [False] and len(error_boxes) == 1
    assert w.files.recent.paths() == [str(second), str(first)]  # a file that failed is not listed
    assert QSettings(w.files.recent._settings.fileName(), QSettings.IniFormat).value("recent/files") == [
        str(second),
        str(first),
    ]
    entries = w.files.recent_menu.entries()
    assert [e.data() for e in entries] == [str(second), str(first)]
    assert w.files.recent_menu.menuAction() in w.menuBar().actions()[0].menu().actions()
    with qtbot.waitSignal(w.fullFrameShown, timeout=TIMEOUT_MS):
        entries[1].trigger()
    assert w.state.source == "first.vti"
    assert w.files.recent.paths() == [str(first), str(second)]


# ---------------------------------------------------------------------------- cancel and supersede
def test_cancel_drops_a_slow_load_and_keeps_the_view(files_window, fakes, qtbot, tmp_path, error_boxes):
    load = ScriptedLoad()
    w = files_window(load=load)
    show(w, qtbot, good_volume())
    volume, frame = w.state.volume, w.viewport.frame
    finished = []
    w.files.loadFinished.connect(finished.append)
    assert not w.files.cancel_action.isEnabled()
    w.files.open_input(tmp_path / "slow.vti")
    qtbot.waitUntil(load.started.is_set, timeout=TIMEOUT_MS)
    assert (
        w.files.busy_bar.isVisible()
        and w.files.cancel_button.isVisible()
        and w.files.cancel_action.isEnabled()
    )
    assert w.files.cancel_action.shortcut() == QKeySequence(Qt.Key_Escape)
    qtbot.mouseClick(w.files.cancel_button, Qt.LeftButton)
    assert finished == [False]
    assert (
        not w.files.busy_bar.isVisible()
        and not w.files.cancel_button.isVisible()
        and not w.files.cancel_action.isEnabled()
    )
    load.release.set()
    assert load.finished.wait(10) and w.files.loader.wait(5000)
    qtbot.wait(100)  # the abandoned result arrives now, and must be dropped
    assert w.state.volume is volume and w.viewport.frame is frame and w.state.source == "ml9"
    assert finished == [False] and error_boxes == []
    assert w.files.recent.paths() == []


def test_escape_cancels_the_load(files_window, fakes, qtbot, tmp_path):
    load = ScriptedLoad()
    w = files_window(load=load)
    w.activateWindow()
    qtbot.waitActive(w)
    w.files.open_input(tmp_path / "slow.vti")
    qtbot.waitUntil(load.started.is_set, timeout=TIMEOUT_MS)
    with qtbot.waitSignal(w.files.loader.cancelled, timeout=TIMEOUT_MS):
        qtbot.keyClick(w.viewport, Qt.Key_Escape)
    load.release.set()
    assert load.finished.wait(10) and w.files.loader.wait(5000)
    qtbot.wait(100)
    assert w.state.volume is None and "No volume" in w.viewport.placeholder


def test_a_new_open_supersedes_a_running_load(files_window, fakes, qtbot, tmp_path, error_boxes):
    load = ScriptedLoad()
    w = files_window(load=load)
    finished = []
    w.files.loadFinished.connect(finished.append)
    w.files.open_input(tmp_path / "slow.vti", renderer="fake")
    qtbot.waitUntil(load.started.is_set, timeout=TIMEOUT_MS)
    with qtbot.waitSignal(w.fullFrameShown, timeout=TIMEOUT_MS):
        w.files.open_input(tmp_path / "fast.vti", renderer="fake")
    assert w.state.source == "fast.vti" and w.state.volume.dimensions == (11, 11, 11)
    assert not w.files.busy_bar.isVisible()
    load.release.set()
    assert load.finished.wait(10) and w.files.loader.wait(5000)
    qtbot.wait(100)
    assert w.state.source == "fast.vti" and finished == [True] and error_boxes == []


def test_stages_show_in_the_status_bar(files_window, fakes, qtbot, tmp_path):
    release = threading.Event()

    def staged(path, tf, scalars, progress):
        progress(f"Reading {Path(path).name}…", None)
        progress("Preparing mesh…", 0.25)
        assert release.wait(15)
        return good_volume()

    w = files_window(load=staged)
    w.files.open_input(tmp_path / "big.vtu", renderer="fake")
    qtbot.waitUntil(lambda: w.files.stage_label.text() == "Preparing mesh…", timeout=TIMEOUT_MS)
    assert (
        w.files.stage_label.isVisible()
        and w.files.busy_bar.maximum() == 100
        and w.files.busy_bar.value() == 25
    )
    with qtbot.waitSignal(w.fullFrameShown, timeout=TIMEOUT_MS):
        release.set()
    assert not w.files.stage_label.isVisible() and w.state.source == "ml9"


def test_loading_a_mesh_prepares_it_and_cancelling_skips_that(monkeypatch, tmp_path):
    from volren.model import tet_mesh

    monkeypatch.setenv(tet_mesh.CACHE_ENV, str(tmp_path / "meshes"))
    volume_file, _ = sample_paths("hollow_cylinder")
    tet_mesh.clear_memory_cache()
    stages = []
    loaded = load_input(volume_file, progress=lambda text, fraction: stages.append((text, fraction)))
    assert stages == [
        ("Reading hollow_cylinder.vtu…", None),
        ("Preparing mesh…", None),
        ("Histograms…", None),
    ]
    assert loaded.volume_path == str(Path(volume_file).absolute()) and loaded.volume.kind == "tet"
    assert tet_mesh.content_key(loaded.volume) in tet_mesh._memory  # the renderer's call is free now
    assert "mean_edge_length" in vars(loaded.volume)

    tet_mesh.clear_memory_cache()
    monkeypatch.setenv(tet_mesh.CACHE_ENV, str(tmp_path / "meshes-2"))

    def stop_before_mesh(text, fraction):
        if text.startswith("Preparing"):
            raise LoadCancelled()

    with pytest.raises(LoadCancelled):
        load_input(volume_file, progress=stop_before_mesh)
    assert not tet_mesh._memory and not (tmp_path / "meshes-2").exists()


# ---------------------------------------------------------------------------- scenes
def test_scene_save_then_open_round_trip(files_window, fakes, qtbot, tmp_path, error_boxes):
    w = files_window()
    with qtbot.waitSignal(w.fullFrameShown, timeout=TIMEOUT_MS):
        w.files.open_input(renderer="fake_2d")  # the bundled sample, read from its file
    sample_file, _ = sample_paths("marschner_lobb")
    assert w.scenes.volume_path == str(Path(sample_file).absolute())
    volume = w.state.volume
    lo, hi = volume.value_range
    tf = TransferFunction2D((lo, hi), (0.0, 2.0), [TFWidget.box((lo, hi), (0.1, 1.0), (0.2, 0.9, 0.4), 0.6)])
    settings = RenderSettings(step=0.3, ambient=0.25, specular=0.05, jitter=True)
    camera = Camera.orbit(volume.bounds, 75.0, -20.0, 1.7, False, w.viewport.aspect())
    crop = (-0.5, 0.8, -1.0, 1.0, -0.25, 0.75)
    with qtbot.waitSignal(w.fullFrameShown, timeout=TIMEOUT_MS):
        w.state.set_transfer_function(tf)
        w.state.set_settings(settings)
        w.state.set_camera(camera)
        w.state.set_background((0.3, 0.2, 0.1))
        w.state.set_crop(crop)
    assert w.state.renderer == "fake_2d"
    scene_path = tmp_path / "saved" / "view.json"
    scene_path.parent.mkdir()
    assert w.scenes.save(scene_path)
    assert w.files.recent.paths()[0] == str(scene_path)

    other = files_window()
    with qtbot.waitSignal(other.fullFrameShown, timeout=TIMEOUT_MS):
        other.files.open_input(scene_path)
    s = other.state
    assert s.transfer_function == tf and s.transfer_function.dims == 2
    assert s.settings == settings and s.renderer == "fake_2d" and s.source == "view.json"
    for name in ("position", "focal_point", "view_up", "clipping_range"):
        np.testing.assert_allclose(getattr(s.camera, name), getattr(camera, name), rtol=1e-12, atol=1e-12)
    assert (s.camera.view_angle, s.camera.parallel) == (camera.view_angle, camera.parallel)
    assert s.background == (0.3, 0.2, 0.1) and s.crop == crop
    np.testing.assert_array_equal(s.volume.values, volume.values)
    assert other.scenes.volume_path == str(Path(sample_file).absolute())
    assert error_boxes == []


def test_a_volume_from_no_file_is_written_beside_the_scene(files_window, fakes, qtbot, tmp_path, error_boxes):
    w = files_window()
    show(w, qtbot, good_volume(13))
    assert w.scenes.volume_path is None
    assert w.scenes.save(tmp_path / "memory.json")
    written = tmp_path / "memory.volume.vti"
    assert written.is_file() and w.scenes.volume_path == str(written)
    reread = load_input(tmp_path / "memory.json")
    assert reread.volume_path == str(written) and reread.renderer == "fake"
    np.testing.assert_allclose(reread.volume.values, w.state.volume.values)
    assert reread.volume.bounds == pytest.approx(w.state.volume.bounds)
    assert error_boxes == []


def test_saving_a_scene_reports_failures(files_window, fakes, qtbot, tmp_path, error_boxes):
    w = files_window()
    assert not w.scenes.save(tmp_path / "empty.json")
    assert "open a volume first" in error_boxes[-1][1]
    show(w, qtbot, good_volume())
    assert not w.scenes.save(tmp_path / "no" / "such" / "folder" / "x.json")
    assert len(error_boxes) == 2 and "x.json" in error_boxes[-1][1] and "\n" not in error_boxes[-1][1]
    assert w.files.recent.paths() == []


def test_save_scene_menu_action_adds_the_suffix(files_window, fakes, qtbot, tmp_path, monkeypatch):
    from PyQt5.QtWidgets import QFileDialog

    w = files_window()
    show(w, qtbot, good_volume())
    offered = []

    def choose(parent, caption, start, filter):
        offered.append(start)
        return str(tmp_path / "chosen"), filter

    monkeypatch.setattr(QFileDialog, "getSaveFileName", choose)
    assert w.scenes.save_action in w.menuBar().actions()[0].menu().actions()
    assert w.scenes.save_action.shortcut() == QKeySequence("Ctrl+S")
    w.scenes.save_action.trigger()
    assert offered == ["scene.json"] and (tmp_path / "chosen.json").is_file()
    assert load_input(tmp_path / "chosen.json").renderer == "fake"


def test_scene_extras_are_checked_and_optional(tmp_path):
    from volren import io

    volume_file, _ = sample_paths("marschner_lobb")
    tf = TransferFunction1D.ramp(0.0, 1.0)
    cam = Camera.orbit(marschner_lobb().bounds, 10.0, 5.0)
    plain = view_scene(volume_file, tf, cam, RenderSettings(), "vtk", (64, 48))
    io.save_scene(plain, tmp_path / "plain.json")
    loaded = load_input(tmp_path / "plain.json")
    assert loaded.crop is None and loaded.background is None and loaded.camera == cam
    assert io.load_scene(tmp_path / "plain.json", load_volume=False).size == (64, 48)
    bad = view_scene(volume_file, tf, cam, RenderSettings(), "vtk", (64, 48), background=(2.0, 0.0, 0.0))
    io.save_scene(bad, tmp_path / "bad.json")
    with pytest.raises(VolrenError, match=r"bad\.json: 'background' must be"):
        load_input(tmp_path / "bad.json")


# ---------------------------------------------------------------------------- screenshots
def test_screenshot_at_a_chosen_size_matches_a_direct_render(
    make_window, ini, fakes, qtbot, tmp_path, error_boxes
):
    from volren.app.rendering.render_service import _registry_factory

    threads = []

    def factory(name):
        threads.append(threading.current_thread())
        return _registry_factory(name)

    w = make_window(settings=ini, renderer_factory=factory)
    show(w, qtbot, good_volume())
    with qtbot.waitSignal(w.fullFrameShown, timeout=TIMEOUT_MS):
        w.state.set_background((0.2, 0.5, 0.7))
    render_thread = threads[0]
    path = tmp_path / "shot.png"
    assert (123, 77) != w.viewport.pixel_size()
    with qtbot.waitSignal(w.screenshots.saved, timeout=TIMEOUT_MS) as saved:
        assert w.screenshots.render(path, 123, 77)
    assert saved.args == [str(path)]
    assert len(threads) == 2 and threads[1] not in (threading.main_thread(), render_thread)  # its own thread
    assert [c["size"] for c in fakes["fake"].calls].count((123, 77)) == 1
    pixels = png_pixels(path)
    assert pixels.shape == (77, 123, 3)
    with registry.create("fake") as direct:
        direct.set_volume(w.state.volume)
        direct.set_transfer_function(w.state.transfer_function)
        expected = to_png_pixels(direct.render(w.state.camera, 123, 77), (0.2, 0.5, 0.7))
    np.testing.assert_array_equal(pixels, expected)
    assert error_boxes == []


def test_screenshot_errors_are_reported(files_window, fakes, qtbot, tmp_path, error_boxes, monkeypatch):
    import volren.io

    w = files_window()
    assert not w.screenshots.render(tmp_path / "x.png", 10, 10)
    assert "open a volume first" in error_boxes[-1][1]
    show(w, qtbot, good_volume())
    assert not w.screenshots.render(tmp_path / "missing" / "dir" / "x.png", 32, 32)
    assert len(error_boxes) == 2 and "x.png" in error_boxes[-1][1] and "\n" not in error_boxes[-1][1]
    taken = tmp_path / "taken.png"
    taken.mkdir()  # not a file: refused before rendering
    assert not w.screenshots.render(taken, 32, 32)
    assert error_boxes[-1][1] == f"{taken}: must be a file, not a folder; choose another path"

    def disk_full(image, path, background) -> None:
        raise VolrenError(f"{path}: cannot write the PNG: No space left on device")

    monkeypatch.setattr(volren.io, "save_image", disk_full)  # fails after rendering
    with qtbot.waitSignal(w.errorReported, timeout=TIMEOUT_MS) as reported:
        assert w.screenshots.render(tmp_path / "full.png", 32, 32)
    assert reported.args[0] == "Cannot save the screenshot" and "full.png" in reported.args[1]
    assert len(error_boxes) == 4


def test_screenshot_menu_action_uses_the_dialog_choice(files_window, fakes, qtbot, tmp_path, monkeypatch):
    w = files_window()
    show(w, qtbot, good_volume())
    asked = []

    def ask(parent, path, size):
        asked.append(size)
        return screenshot_dialog.ScreenshotChoice(str(tmp_path / "menu.png"), 64, 40)

    monkeypatch.setattr(screenshot_dialog, "ask_screenshot", ask)
    assert w.screenshots.action in w.menuBar().actions()[0].menu().actions()
    with qtbot.waitSignal(w.screenshots.saved, timeout=TIMEOUT_MS):
        w.screenshots.action.trigger()
    assert asked == [w.viewport.pixel_size()]
    assert png_pixels(tmp_path / "menu.png").shape == (40, 64, 3)

    monkeypatch.setattr(
        screenshot_dialog,
        "ask_screenshot",
        lambda *a: screenshot_dialog.ScreenshotChoice(str(tmp_path / "w.png"), 1, 1, True),
    )
    with qtbot.waitSignal(w.screenshots.saved, timeout=TIMEOUT_MS):
        w.screenshots.action.trigger()
    assert png_pixels(tmp_path / "w.png").shape == (w.height(), w.width(), 3)


def test_screenshot_dialog_size_aspect_and_whole_window(qtbot, tmp_path):
    dialog = screenshot_dialog.ScreenshotDialog(None, str(tmp_path / "shot"), (400, 200))
    qtbot.addWidget(dialog)
    assert (dialog.width_box.value(), dialog.height_box.value()) == (400, 200)
    dialog.width_box.setValue(1000)
    assert dialog.height_box.value() == 500  # the viewport's aspect is kept
    dialog.keep_aspect.setChecked(False)
    dialog.height_box.setValue(300)
    assert dialog.width_box.value() == 1000
    assert dialog.choice() == screenshot_dialog.ScreenshotChoice(str(tmp_path / "shot.png"), 1000, 300, False)
    dialog.whole_window.setChecked(True)
    assert not dialog.width_box.isEnabled() and dialog.choice().whole_window
    dialog.path_edit.setText("")
    assert not dialog.buttons.button(dialog.buttons.Save).isEnabled()


@pytest.mark.vtk
def test_vtk_screenshot_renders_beside_the_viewport_renderer(
    make_window, ini, sample, qtbot, tmp_path, error_boxes
):
    """The screenshot's VTK renderer (own thread, own context) draws what the viewport's draws."""
    w = make_window(settings=ini)
    show(w, qtbot, sample, "vtk")
    width, height = w.viewport.pixel_size()
    path = tmp_path / "vtk.png"
    with qtbot.waitSignal(w.screenshots.saved, timeout=TIMEOUT_MS):
        w.screenshots.render(path, width, height)
    pixels = png_pixels(path)
    shown = w.viewport.frame.rgb
    assert np.abs(pixels.astype(int) - shown).max() <= 2, "the screenshot differs from the frame on screen"
    background = np.round(np.asarray(w.state.background) * 255)
    assert np.count_nonzero(np.abs(pixels - background).max(axis=-1) > 30) > 0.05 * width * height
    assert error_boxes == []


def test_dialogs_start_where_the_person_last_opened_or_saved(make_window, ini, qtbot, tmp_path, monkeypatch):
    """Issue 23: the Open dialog starts in the folder last used (kept across sessions), Save
    Scene proposes that folder (not the data's), and so does the first screenshot."""
    from PyQt5.QtWidgets import QFileDialog

    from volren.app.files import screenshot_dialog

    work, data = tmp_path / "work", tmp_path / "data"
    work.mkdir()
    data.mkdir()
    w = make_window(settings=ini)
    assert w.files.recent.folder() == ""  # nothing yet: the working folder
    w.files.recent.remember_folder(work / "earlier.json")
    asked = {}

    def open_dialog(parent, title, start, filters):
        asked["open"] = start
        return "", ""

    monkeypatch.setattr(QFileDialog, "getOpenFileName", staticmethod(open_dialog))
    w.files._open_dialog()
    assert asked["open"] == str(work)
    assert RecentFiles(QSettings(ini.fileName(), QSettings.IniFormat)).folder() == str(work)  # kept
    w.scenes._volume_path = str(data / "head.vti")
    assert w.scenes.suggested_path() == str(work / "head.json")

    def ask(parent, path, size):
        asked["screenshot"] = path
        return None

    monkeypatch.setattr(screenshot_dialog, "ask_screenshot", ask)
    w.screenshots._dialog()
    assert asked["screenshot"] == str(work / "volren.png")
    w.files.recent.add(data / "head.vti")  # opening a file moves the work there
    assert w.files.recent.folder() == str(data)


def test_a_slow_screenshot_without_progress_reports_shows_a_busy_dialog_with_the_time(
    files_window, fakes, qtbot, tmp_path, monkeypatch
):
    """Issue 23: a renderer that reports no progress gave no feedback for the whole screenshot
    (a QProgressDialog shows itself only from setValue); now it shows, busy, counting seconds."""
    import time as clock

    from volren.renderers.registry import registry

    class SlowFrame(fakes["fake"]):
        name: ClassVar[str] = "fake_slow_frame"

        def _render(self, camera, width, height, progress):
            clock.sleep(1.5)
            return super()._render(camera, width, height, progress)

    registry.register("fake_slow_frame", SlowFrame, replace=True)
    try:
        w = files_window()
        show(w, qtbot, good_volume())
        w.state.set_renderer("fake_slow_frame")
        with qtbot.waitSignal(w.screenshots.saved, timeout=TIMEOUT_MS):
            assert w.screenshots.render(tmp_path / "slow.png", 32, 32)
            progress = w.screenshots._progress.dialog
            qtbot.waitUntil(
                lambda: progress.isVisible() and progress.labelText().endswith(" s"), timeout=1500
            )
            assert progress.maximum() == 0  # busy: no percentage to show
            assert "fake_slow_frame" in progress.labelText()
        assert (tmp_path / "slow.png").exists() and w.screenshots._progress is None
    finally:
        registry.unregister("fake_slow_frame")


# ---------------------------------------------------------------------------- choosing the array
def test_the_dataset_panel_switches_fields_keeping_the_view_and_each_fields_tf(
    files_window, fakes, qtbot, tmp_path
):
    """Issue 23: choose the scalar array (and a vector's component or magnitude) in the app; the
    Dataset panel names the array shown."""
    import pyvista as pv

    rng = np.random.default_rng(5)
    grid = pv.ImageData(dimensions=(6, 5, 4), spacing=(1.0, 0.5, 2.0))
    density = rng.uniform(0, 10, grid.n_points).astype(np.float32)
    velocity = rng.normal(size=(grid.n_points, 3)).astype(np.float32)
    grid.point_data["density"] = density
    grid.point_data["velocity"] = velocity
    path = tmp_path / "flow.vti"
    grid.save(path)
    w = files_window()
    with qtbot.waitSignal(w.fullFrameShown, timeout=TIMEOUT_MS):
        w.files.open_input(path, renderer="fake")
    panel, box = w.docks.dataset, w.docks.dataset.array_box
    labels = [box.itemText(i) for i in range(box.count())]
    assert labels == ["density", "velocity (magnitude)", "velocity (x)", "velocity (y)", "velocity (z)"]
    assert box.isEnabled() and box.currentText() == "density" and panel.facts()["Array"] == "density"
    edited = TransferFunction1D.ramp(2, 8, 0.7)
    w.state.set_transfer_function(edited)
    w.state.set_camera(w.state.camera.azimuth(40).elevation(10))
    camera, renderer = w.state.camera, w.state.renderer

    def choose(label: str) -> None:
        index = labels.index(label)
        with qtbot.waitSignal(w.files.loadFinished, timeout=TIMEOUT_MS):
            box.setCurrentIndex(index)
            box.activated.emit(index)

    choose("velocity (y)")
    volume = w.state.volume
    assert volume.scalars == "velocity:y" and panel.facts()["Array"] == "velocity (y)"
    np.testing.assert_array_equal(volume.values.reshape(-1), velocity[:, 1])
    assert w.state.camera == camera and w.state.renderer == renderer
    low, high = volume.value_range
    assert w.state.transfer_function is not edited
    assert w.state.transfer_function.value_range == pytest.approx(
        (low, high)
    )  # the default TF over this field
    choose("velocity (magnitude)")
    np.testing.assert_allclose(w.state.volume.values.reshape(-1), np.linalg.norm(velocity, axis=1), rtol=1e-6)
    choose("density")
    assert w.state.transfer_function is edited  # each field keeps the TF edited for it
    assert box.currentText() == "density" and w.state.camera == camera


def test_the_array_chooser_is_disabled_with_why_where_there_is_no_choice(files_window, fakes, qtbot):
    w = files_window()
    box = w.docks.dataset.array_box
    assert not box.isEnabled() and box.toolTip() == "Open a volume first"
    show(w, qtbot, good_volume())  # made in memory
    assert not box.isEnabled() and "not read from a file" in box.toolTip()
    assert not w.files.show_array("anything")
