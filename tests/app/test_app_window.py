"""The main window under pytest-qt (offscreen): frames, gestures, renderers, files, screenshots."""

from __future__ import annotations

import os
import stat
from collections.abc import Callable

import numpy as np
import pytest
from PyQt5.QtCore import QMimeData, QPoint, QPointF, Qt, QUrl
from PyQt5.QtGui import QDragEnterEvent, QDropEvent, QImage, QWheelEvent
from PyQt5.QtWidgets import QApplication

from volren.app.core.frame_sizes import preview_size
from volren.app.core.loading import LoadedInput
from volren.app.core.state import default_camera
from volren.errors import VolrenError
from volren.model.scene_class import SceneClass
from volren.model.transfer_function import TransferFunction1D
from volren.quality import Measurement, QualityTable
from volren.renderers.base import QualityLevel
from volren.samples import sample_transfer_functions

pytestmark = [pytest.mark.qt, pytest.mark.vtk]

#: Generous: the first VTK frame creates an EGL context; later frames take tens of ms.
FRAME_TIMEOUT_MS = 20000


def measured(
    label: str, step: float, pre: bool, options: dict, ms: dict, worst: float, meets: bool = True
) -> Measurement:
    """A measured level whose peer took 1 ms on every scene (ratios rank as frame times)."""
    return Measurement(QualityLevel(label, step, pre, options), ms, dict.fromkeys(ms, 1.0), worst, meets)


def use_levels(monkeypatch, levels: dict) -> QualityTable:
    """Replace the measured quality table by `levels` (renderer -> level -> Measurement) of uniform volumes."""
    from volren import quality

    table = QualityTable({SceneClass("uniform"): levels}, {})
    monkeypatch.setattr(quality, "table", lambda: table)
    return table


def level(step: float, pre: bool = False, options: dict | None = None, ms: float = 10.0) -> Measurement:
    """A measured level: `step`, pre-integration, `options`, `ms` on one scene, VTK's error."""
    return measured(f"step {step}", step, pre, options or {}, {"a/smooth": ms}, 1.0)


def frame_pixels(window) -> np.ndarray:
    frame = window.viewport.frame
    assert frame is not None
    return frame.rgb


def not_background(window) -> int:
    """How many pixels of the shown frame differ clearly from the background colour."""
    bg = np.round(np.asarray(window.state.background) * 255)
    return int(np.count_nonzero(np.abs(frame_pixels(window).astype(float) - bg).max(axis=-1) > 30))


def test_window_opens_on_sample_and_shows_first_full_frame(loaded_window, error_boxes):
    w = loaded_window
    frame = w.viewport.frame
    assert frame.full and frame.renderer == "vtk"
    assert (frame.width, frame.height) == w.viewport.pixel_size()
    assert not_background(w) > 0.05 * frame.width * frame.height, "the volume is not visible"
    assert (
        "vtk" in w.renderers.frame_label.text()
        and f"{frame.width} x {frame.height}" in w.renderers.frame_label.text()
    )
    assert "ms" in w.renderers.frame_label.text()
    assert w.renderers.chooser.currentText() == "vtk"
    assert "marschner_lobb" in w.windowTitle()
    assert error_boxes == []


def drag(
    qtbot, widget, button, start: QPoint, moves: list[QPoint], holding: Callable[[], bool] | None = None
) -> None:
    """Press, move and release on `widget` (positions in its coordinates), as real input does; with
    `holding`, the button is held after the moves until it returns True (a person who pauses).

    The events go to the widget's QWindow: in Qt 5 QTest's QWidget overload of mouseMove only
    moves the cursor, which delivers nothing on the offscreen platform, whereas the QWindow
    overload feeds the window-system queue, so press, moves and release arrive with the button
    state a real drag has.
    """
    window = widget.window().windowHandle()

    def to_window(p: QPoint) -> QPoint:
        return widget.mapTo(widget.window(), p)

    qtbot.mousePress(window, button, pos=to_window(start))
    for p in moves:
        qtbot.mouseMove(window, to_window(p))
    if holding is not None:
        qtbot.waitUntil(holding, timeout=FRAME_TIMEOUT_MS)
    qtbot.mouseRelease(window, button, pos=to_window(moves[-1]))


def test_drag_rotates_with_preview_frames_then_one_full_frame(loaded_window, qtbot, error_boxes):
    w = loaded_window
    before = w.state.camera
    frames = []
    w.frameShown.connect(frames.append)
    c = w.viewport.rect().center()
    moves = [c + QPoint(10 * i, 3 * i) for i in range(1, 6)]
    previewed = lambda: any(not f.full for f in frames)  # noqa: E731 - held until a preview shows
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        drag(qtbot, w.viewport, Qt.LeftButton, c, moves, holding=previewed)
    after = w.state.camera
    assert not np.allclose(after.position, before.position), "left-drag did not rotate"
    assert np.allclose(after.focal_point, before.focal_point)
    assert abs(np.dot(after.view_up, after.direction)) < 1e-9, "view up not orthogonalized"
    full_size = w.viewport.pixel_size()
    previews = [f for f in frames if not f.full]
    assert previews, "no reduced-cost frame while dragging"
    # at most a quarter of the pixels (fewer if this machine renders slowly), same aspect
    half_w, half_h = preview_size(*full_size, 0.5)
    assert all(1 <= f.width <= half_w and 1 <= f.height <= half_h for f in previews)
    assert all(abs(f.width / f.height - full_size[0] / full_size[1]) < 0.1 for f in previews)
    last = frames[-1]
    assert last.full and (last.width, last.height) == full_size
    assert last.camera == after
    assert frames.index(previews[0]) < frames.index(last)
    assert error_boxes == []


def test_right_drag_and_wheel_dolly_middle_drag_pans(loaded_window, qtbot):
    w = loaded_window
    c = w.viewport.rect().center()
    d0 = w.state.camera.distance
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        drag(qtbot, w.viewport, Qt.RightButton, c, [c + QPoint(0, -20), c + QPoint(0, -40)])
    d1 = w.state.camera.distance
    assert d1 < d0, "dragging up with the right button should dolly in"

    wheel = QWheelEvent(
        QPointF(c),
        QPointF(w.viewport.mapToGlobal(c)),
        QPoint(),
        QPoint(0, -120),
        Qt.NoButton,
        Qt.NoModifier,
        Qt.NoScrollPhase,
        False,
    )
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        QApplication.sendEvent(w.viewport, wheel)
    assert w.state.camera.distance == pytest.approx(d1 * 1.1**2), "a wheel notch back dollies out by 1.1^2"

    focal = np.array(w.state.camera.focal_point)
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        drag(qtbot, w.viewport, Qt.MiddleButton, c, [c + QPoint(15, 0), c + QPoint(30, 0)])
    assert not np.allclose(w.state.camera.focal_point, focal), "middle-drag did not pan"


def test_r_resets_the_view(loaded_window, qtbot):
    w = loaded_window
    c = w.viewport.rect().center()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        drag(qtbot, w.viewport, Qt.LeftButton, c, [c + QPoint(50, 20)])
    assert w.state.camera != default_camera(w.state.volume, w.viewport.aspect())
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        qtbot.keyClick(w.viewport, Qt.Key_R)
    assert w.state.camera == default_camera(w.state.volume, w.viewport.aspect())


def test_resize_renders_at_the_new_size(loaded_window, qtbot):
    w = loaded_window
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS) as blocker:
        w.resize(420, 330)
    assert (blocker.args[0].width, blocker.args[0].height) == w.viewport.pixel_size()


def test_switching_renderer_keeps_camera_and_tf(loaded_window, fake_renderers, qtbot, error_boxes):
    w = loaded_window
    w.renderers.refresh()  # the fakes were registered after the window was made
    camera, tf = w.state.camera, w.state.transfer_function
    index = w.renderers.chooser.findText("fake")
    assert index >= 0 and w.renderers.chooser.is_enabled("fake")
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS) as blocker:
        w.renderers.chooser.setCurrentIndex(index)
        w.renderers.chooser.activated.emit(index)
    assert blocker.args[0].renderer == "fake" and w.state.renderer == "fake"
    assert w.state.camera is camera and w.state.transfer_function is tf
    seen = fake_renderers["fake"].calls[-1]
    assert seen["camera"] == camera and seen["tf"] == tf
    assert seen["size"] == w.viewport.pixel_size()
    assert "fake" in w.renderers.frame_label.text()

    vtk_index = w.renderers.chooser.findText("vtk")
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS) as blocker:
        w.renderers.chooser.setCurrentIndex(vtk_index)
        w.renderers.chooser.activated.emit(vtk_index)
    assert blocker.args[0].renderer == "vtk" and blocker.args[0].camera == camera
    assert error_boxes == []


def test_renderer_that_cannot_draw_the_volume_is_disabled_with_tooltip(
    make_window, fake_renderers, sample, qtbot
):
    w = make_window()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.files.apply_loaded(sample, "vtk")
    assert "fake_tet_only" in w.renderers.chooser.names()
    assert not w.renderers.chooser.is_enabled("fake_tet_only")
    assert "does not render uniform volumes" in w.renderers.chooser.tooltip("fake_tet_only")
    assert w.renderers.chooser.is_enabled("vtk") and w.renderers.chooser.is_enabled("fake")
    # picking the disabled entry anyway (e.g. by keyboard) changes nothing
    w.renderers.chooser.activated.emit(w.renderers.chooser.findText("fake_tet_only"))
    assert w.state.renderer == "vtk"


def test_renderer_that_raises_reports_and_falls_back(loaded_window, fake_renderers, qtbot, error_boxes):
    w = loaded_window
    w.renderers.refresh()
    camera = w.state.camera
    index = w.renderers.chooser.findText("fake_broken")
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS) as blocker:
        w.renderers.chooser.setCurrentIndex(index)
        w.renderers.chooser.activated.emit(index)
    assert len(error_boxes) == 1
    title, text = error_boxes[0]
    assert "\n" not in text and "shader did not compile" in text and "vtk" in text
    assert w.state.renderer == "vtk" and w.renderers.chooser.currentText() == "vtk"
    assert blocker.args[0].renderer == "vtk" and w.state.camera is camera


def inside_camera(bounds):
    """A perspective camera with its eye inside `bounds`, looking at their far corner."""
    from volren.model import Camera

    lo, hi = np.asarray(bounds[0::2]), np.asarray(bounds[1::2])
    return Camera(position=tuple(lo + 0.4 * (hi - lo)), focal_point=tuple(hi), clipping_range=(0.01, 100.0))


def test_a_renderer_that_cannot_draw_a_view_from_inside_gives_way_to_one_that_can(make_window, fake_renderers,
                                                                                   sample, qtbot, error_boxes):  # fmt: skip
    w = make_window()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.files.apply_loaded(sample, "fake_outside_only")
    assert w.state.renderer == "fake_outside_only" and error_boxes == []
    inside = inside_camera(w.state.volume.bounds)
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS) as blocker:
        w.state.set_camera(inside)
    drawn = blocker.args[0].renderer
    assert drawn not in ("fake_outside_only", "reference") and w.state.renderer == drawn
    assert (
        len(error_boxes) == 1
        and "inside" in error_boxes[0][1]
        and f"switched to {drawn}" in error_boxes[0][1]
    )
    assert blocker.args[0].camera == inside


def test_requested_renderer_that_cannot_draw_is_an_error(
    make_window, fake_renderers, sample, qtbot, error_boxes
):
    """The error says so, and the renderer drawing instead is `auto`'s measured choice (it was a
    fixed preference for vtk, the slowest renderer on the shared scenes)."""
    from volren.quality import DEFAULT_LEVEL, choose_renderer

    w = make_window()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS) as blocker:
        w.files.apply_loaded(sample, "fake_tet_only")
    usable = [o.name for o in w.renderers.options() if o.enabled]
    measured, _ = choose_renderer(SceneClass.of(sample.volume, sample.transfer_function), DEFAULT_LEVEL, 1,
                                  w.state.settings, usable, can_draw=set(usable).__contains__)  # fmt: skip
    assert blocker.args[0].renderer == measured and measured != "vtk"
    assert len(error_boxes) == 1 and "fake_tet_only does not render uniform volumes" in error_boxes[0][1]


def fake_load(path, tf, scalars):
    """An injected loader: 'good*' files load a small volume, anything else fails like a reader."""
    from volren.samples import marschner_lobb

    if str(path).endswith("good.vti"):
        return LoadedInput(
            marschner_lobb(17), sample_transfer_functions()["marschner_lobb"], source="good.vti"
        )
    raise VolrenError(f"{path}: not a VTK XML image file")


def test_opening_a_bad_file_keeps_the_volume_and_reports_one_line(
    make_window, sample, qtbot, error_boxes, tmp_path
):
    w = make_window(load=fake_load)
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.files.apply_loaded(sample, "vtk")
    volume, frame = w.state.volume, w.viewport.frame
    with qtbot.waitSignal(w.files.loadFinished, timeout=FRAME_TIMEOUT_MS) as blocker:
        w.files.open_input(tmp_path / "bad.vti")
    assert blocker.args == [False]
    assert w.state.volume is volume and w.viewport.frame is frame
    assert len(error_boxes) == 1 and "bad.vti" in error_boxes[0][1] and "\n" not in error_boxes[0][1]
    assert not w.files.busy_bar.isVisible()


def test_dropping_a_file_opens_it_off_the_gui_thread(make_window, sample, qtbot, tmp_path, error_boxes):
    w = make_window(load=fake_load)
    path = tmp_path / "good.vti"
    mime = QMimeData()
    mime.setUrls([QUrl.fromLocalFile(str(path))])
    enter = QDragEnterEvent(QPoint(20, 20), Qt.CopyAction, mime, Qt.LeftButton, Qt.NoModifier)
    QApplication.sendEvent(w, enter)
    assert enter.isAccepted(), "the window refuses a local file"
    drop = QDropEvent(QPointF(20, 20), Qt.CopyAction, mime, Qt.LeftButton, Qt.NoModifier)
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        QApplication.sendEvent(w, drop)  # Qt delivers a drop only after an accepted drag-enter
        assert w.files.busy_bar.isVisibleTo(w)  # the busy indicator shows while the loader runs
    assert w.state.volume.dimensions == (17, 17, 17) and w.state.source == "good.vti"
    assert error_boxes == []


def test_save_screenshot_writes_a_png_of_the_viewport_size(loaded_window, tmp_path):
    w = loaded_window
    path = tmp_path / "shot.png"
    assert w.screenshots.save(path)
    image = QImage(str(path))
    assert not image.isNull()
    assert (image.width(), image.height()) == w.viewport.pixel_size()
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    whole = tmp_path / "window.png"
    assert w.screenshots.save(whole, whole_window=True)
    assert (QImage(str(whole)).width(), QImage(str(whole)).height()) == (w.width(), w.height())


def test_save_screenshot_to_a_bad_place_reports(loaded_window, tmp_path, error_boxes):
    assert not loaded_window.screenshots.save(tmp_path / "missing" / "dir" / "x.png")
    assert len(error_boxes) == 1 and "x.png" in error_boxes[0][1]
    try:  # a node like /dev/null: Qt wrote into it and said it had saved
        os.mknod(tmp_path / "null.png", 0o666 | stat.S_IFCHR, os.makedev(1, 3))
    except PermissionError:
        pytest.skip("this user may not make device nodes")
    assert not loaded_window.screenshots.save(tmp_path / "null.png")
    assert error_boxes[1][1] == f"{tmp_path / 'null.png'}: must be a file, not a device; choose another path"


def test_in_place_tf_edit_renders_again(loaded_window, qtbot):
    w = loaded_window
    before = frame_pixels(w).copy()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.state.transfer_function.set_opacity_points([[0.0, 0.0], [1.0, 0.0]])  # fully transparent
    assert not np.array_equal(frame_pixels(w), before)
    assert not_background(w) == 0


def test_opens_the_bundled_sample_by_default(window, qtbot, error_boxes):
    with qtbot.waitSignal(window.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        window.files.open_input()
    assert window.state.source == "sample marschner_lobb" and window.state.volume.dimensions == (41, 41, 41)
    assert not_background(window) > 0
    assert error_boxes == []


def test_opening_a_scene_then_a_tf_file(window, qtbot, tmp_path, error_boxes):
    from volren import io
    from volren.model.scene import OrbitView, Scene
    from volren.samples import sample_paths

    volume_path, tf_path = sample_paths("marschner_lobb")
    scene_path = tmp_path / "scene.json"
    view = OrbitView(azimuth=90.0, elevation=10.0, zoom=1.5)
    io.save_scene(
        Scene(str(volume_path), io.load_transfer_function(tf_path), view, renderer="vtk"), scene_path
    )
    with qtbot.waitSignal(window.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        window.files.open_input(scene_path)
    volume = window.state.volume
    assert window.state.camera == view.camera(volume.bounds, window.viewport.aspect())
    assert window.state.source == "scene.json"

    tf = TransferFunction1D.ramp(0.0, 1.0, 0.5, (1.0, 0.0, 0.0), 0.05)
    io.save_transfer_function(tf, tmp_path / "red.json")
    with qtbot.waitSignal(window.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        window.files.open_input(tmp_path / "red.json")
    assert window.state.volume is volume and window.state.transfer_function == tf
    red = frame_pixels(window)[..., 0].astype(int) - frame_pixels(window)[..., 1]
    assert np.count_nonzero(red > 60) > 100, "the red TF is not what is shown"
    assert error_boxes == []


def test_opening_a_corrupt_file_with_the_real_readers(loaded_window, qtbot, error_boxes, tmp_path):
    w = loaded_window
    volume = w.state.volume
    bad = tmp_path / "corrupt.vti"
    bad.write_bytes(b"this is not a VTK file\x00\x01")
    with qtbot.waitSignal(w.files.loadFinished, timeout=FRAME_TIMEOUT_MS) as blocker:
        w.files.open_input(bad)
    assert blocker.args == [False] and w.state.volume is volume
    assert len(error_boxes) == 1 and "corrupt.vti" in error_boxes[0][1] and "\n" not in error_boxes[0][1]


def test_opening_a_2d_tf_switches_to_a_renderer_that_draws_it(loaded_window, qtbot, error_boxes, tmp_path):
    """vtk draws 1D TFs only: a 2D TF keeps the volume, disables vtk with the reason and moves
    the view to a renderer that can draw it, without an error box."""
    from volren import io
    from volren.model import TFWidget, TransferFunction2D

    w = loaded_window
    volume = w.state.volume
    lo, hi = volume.value_range
    tf2 = TransferFunction2D((lo, hi), (0.0, 1.0), [TFWidget.box((lo, hi), (0.0, 1.0), (1.0, 1.0, 1.0), 0.5)])
    io.save_transfer_function(tf2, tmp_path / "tf2d.json")
    assert w.state.renderer == "vtk"
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS) as blocker:
        w.files.open_input(tmp_path / "tf2d.json")
    assert w.state.volume is volume and w.state.transfer_function == tf2
    assert w.state.renderer != "vtk" and blocker.args[0].renderer == w.state.renderer
    vtk_option = next(o for o in w.renderers.options() if o.name == "vtk")
    assert not vtk_option.enabled and "2D" in vtk_option.reason
    assert error_boxes == []


def test_run_with_screenshot_in_process(qapp, tmp_path):
    from volren.app.main import run

    out = tmp_path / "window.png"
    assert run(renderer="vtk", screenshot=out, size=(1300, 720)) == 0
    image = QImage(str(out))
    assert (image.width(), image.height()) == (1300, 720)


def test_the_first_volume_gets_the_auto_renderer_and_the_status_bar_says_why(
    make_window, sample, qtbot, error_boxes
):
    from volren.quality import DEFAULT_LEVEL, choose_renderer
    from volren.renderers.registry import registry

    w = make_window()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS) as blocker:
        w.files.apply_loaded(sample)  # no renderer named: auto
    kind = SceneClass.of(sample.volume, sample.transfer_function)  # the TF's class chooses too
    expected, _ = choose_renderer(kind, DEFAULT_LEVEL, 1, w.state.settings, registry.names())
    assert w.state.renderer == blocker.args[0].renderer == expected != "auto"
    assert (
        f"renderer {expected}: " in w.statusBar().currentMessage()
        and "(auto)" in w.statusBar().currentMessage()
    )
    assert error_boxes == []


def test_a_volume_of_the_other_kind_gets_auto_and_a_renderer_picked_by_hand_stays(make_window, sample, qtbot,
                                                                                  error_boxes):  # fmt: skip
    """Opening a mesh from a window showing a grid took vtk (a fixed preference: the slowest
    renderer, and the least accurate there); it takes `auto`'s measured choice, as the first
    volume does. A renderer the person picked stays for the next volume it can draw."""
    from volren.quality import DEFAULT_LEVEL, choose_renderer
    from volren.samples import hollow_cylinder

    def auto_choice(loaded: LoadedInput) -> str:
        usable = [o.name for o in w.renderers.options() if o.enabled]
        kind = SceneClass.of(loaded.volume, loaded.transfer_function)
        return choose_renderer(
            kind, DEFAULT_LEVEL, 1, w.state.settings, usable, can_draw=set(usable).__contains__
        )[0]

    mesh = hollow_cylinder()
    tets = LoadedInput(mesh, TransferFunction1D.ramp(*mesh.value_range, 0.6), source="hollow_cylinder")
    w = make_window()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.files.apply_loaded(sample)
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS) as blocker:
        w.files.apply_loaded(tets)
    assert w.state.renderer == blocker.args[0].renderer == auto_choice(tets) != "vtk"
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.renderers.chooser.rendererChosen.emit("vtk")  # picked by hand
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.files.apply_loaded(sample)
    assert w.state.renderer == "vtk" != auto_choice(sample) and not w.renderers.auto
    assert error_boxes == []


@pytest.mark.usefixtures("opengl")  # the slicer draws the 2D TF
def test_a_2d_tf_from_a_band_tf_switches_to_a_renderer_that_draws_it(make_window, sample, qtbot, error_boxes):
    """A band TF opens with pre-integration (its measured level), which no renderer has for 2D
    TFs: "Use a 2D transfer function" left raycast in place and every frame failed ("does not
    support 2D transfer functions"); the renderer and settings now move to ones that draw it."""
    from volren.model.tf_class import TFClass

    lo, hi = sample.volume.value_range
    mid, span = 0.5 * (lo + hi), hi - lo
    band = TransferFunction1D([[lo, 1, 1, 1], [hi, 1, 0.5, 0]],
                              [[lo, 0], [mid - 0.02 * span, 0], [mid, 0.9], [mid + 0.02 * span, 0], [hi, 0]])  # fmt: skip
    assert TFClass.of(band, (lo, hi)) == TFClass.BAND
    w = make_window()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.files.apply_loaded(LoadedInput(sample.volume, band, source="band"))
    assert w.state.settings.preintegration  # the band level
    submitted = []  # every frame asked for: none may go to a renderer that refuses it (a race with the fix)
    submit = w.service.submit
    w.service.submit = lambda name, volume, tf, settings, *rest: (
        submitted.append((name, tf.dims, settings)), submit(name, volume, tf, settings, *rest))[1]  # fmt: skip
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS) as blocker:
        w.docks.tf_panel.editor_2d.use_2d_transfer_function()
    assert w.state.transfer_function.dims == 2 and blocker.args[0].renderer == w.state.renderer
    caps = w.registry.capabilities(w.state.renderer)
    assert caps.unsupported_reason("uniform", 2, w.state.settings) is None
    refused = [(name, dims) for name, dims, settings in submitted
               if w.registry.capabilities(name).unsupported_reason("uniform", dims, settings) is not None]  # fmt: skip
    assert submitted and refused == []
    assert error_boxes == []


def test_a_long_renderer_set_up_says_preparing_until_the_frame(make_window, fake_renderers, sample, qtbot):
    """A set-up over 0.3 s (the slow fake takes 0.8 s to take the volume) shows "preparing" in the
    frame label, and the frame's numbers replace it; a quick renderer never shows it."""
    w = make_window()
    seen = []
    w.renderers.frame_label.setText("")
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.files.apply_loaded(sample, "fake_slow_setup")
        qtbot.waitUntil(lambda: "preparing" in w.renderers.frame_label.text(), timeout=2000)
        seen.append(w.renderers.frame_label.text())
    assert seen == ["fake_slow_setup  |  preparing the renderer…"]
    qtbot.waitUntil(lambda: "ms" in w.renderers.frame_label.text(), timeout=2000)
    assert "preparing" not in w.renderers.frame_label.text()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.state.set_renderer("fake")
    qtbot.wait(400)
    assert "preparing" not in w.renderers.frame_label.text()


def test_resting_before_release_draws_one_full_frame_not_two(loaded_window, qtbot):
    """Input quiet during a drag gives a full frame; the release that follows, with the camera
    unchanged, must not draw the same full frame again (issue 22: duplicate frames)."""
    w = loaded_window
    frames = []
    w.frameShown.connect(frames.append)
    window = w.viewport.window().windowHandle()
    c = w.viewport.mapTo(w, w.viewport.rect().center())
    qtbot.mousePress(window, Qt.LeftButton, pos=c)
    for i in range(1, 4):
        qtbot.mouseMove(window, c + QPoint(8 * i, 2 * i))
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        pass  # resting: the settle timer asks for the full frame
    qtbot.mouseRelease(window, Qt.LeftButton, pos=c + QPoint(24, 6))
    qtbot.wait(600)  # longer than the settle time: a second full frame would have come by now
    full = [f for f in frames if f.full]
    assert len(full) == 1 and full[0].camera == w.state.camera
    assert any(not f.full for f in frames)  # the drag itself previewed
    # a later change still draws
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.reset_view()


def test_the_release_asks_for_the_full_frame_without_waiting_for_quiet_input(loaded_window, qtbot):
    """A release ends the gesture: the full frame is requested then, not after the settle time
    that only a drag resting before its release waits for (set to a minute here)."""
    w = loaded_window
    w.scheduler._timer.setInterval(60_000)
    window = w.viewport.window().windowHandle()
    c = w.viewport.mapTo(w, w.viewport.rect().center())
    qtbot.mousePress(window, Qt.LeftButton, pos=c)
    for i in range(1, 4):
        qtbot.mouseMove(window, c + QPoint(8 * i, 2 * i))
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        qtbot.mouseRelease(window, Qt.LeftButton, pos=c + QPoint(24, 6))
    assert w.state.camera is not None


def test_the_quality_chooser_applies_the_measured_settings_and_a_switch_drops_foreign_options(
    make_window, sample, qtbot, monkeypatch
):
    draft = measured("step 2, table 64", 2.0, True, {"table_size": 64}, {"a/smooth": 10.0}, 3.0)
    use_levels(monkeypatch, {"slicer": {"draft": draft}})
    w = make_window()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.files.apply_loaded(sample, "slicer")
    combo = w.quality.chooser
    model = combo.model()
    assert combo.currentText() == "custom"
    assert (
        model.item(combo.findText("draft")).isEnabled()
        and not model.item(combo.findText("exact")).isEnabled()
    )
    assert "step 2, table 64" in model.item(combo.findText("draft")).toolTip()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        combo.activated.emit(combo.findText("draft"))
    s = w.state.settings
    assert (s.step, s.preintegration, dict(s.options)) == (2.0, True, {"table_size": 64})
    assert combo.currentText() == "draft"
    w.state.set_settings(
        s.with_(step=1.0, preintegration=False)
    )  # any other edit: custom (vtk: no pre-integration on grids)
    assert combo.currentText() == "custom"
    # vtk has no table_size option: switching drops it instead of failing the frame
    shown = []
    w.fullFrameShown.connect(shown.append)
    w.renderers.switch("vtk")
    qtbot.waitUntil(lambda: any(f.renderer == "vtk" for f in shown), timeout=FRAME_TIMEOUT_MS)
    assert dict(w.state.settings.options) == {} and w.state.renderer == "vtk"
    assert not model.item(combo.findText("draft")).isEnabled()  # nothing measured for vtk in this table


def test_the_first_volume_opens_at_the_app_level_and_a_switch_keeps_the_level(
    make_window, sample, qtbot, monkeypatch
):
    """What the app shows with no options is the `default` level's measured settings, as the CLI's
    (its previews are at `interactive`); switching renderer gives the new renderer's settings at the
    level chosen, even through a renderer whose levels are all equal (the box showed the first of
    them, draft, and the next renderer got draft's settings); custom settings stay custom; the frame
    label names the level drawn."""
    use_levels(monkeypatch, {"slicer": {"default": level(0.5, True, {"table_size": 128}),
                                        "draft": level(2.0, False, {"table_size": 64})},
                             "vtk": {name: level(0.75) for name in ("draft", "interactive", "default")}})  # fmt: skip
    w = make_window()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.files.apply_loaded(sample, "slicer")
    s = w.state.settings
    assert (s.step, s.preintegration, dict(s.options)) == (0.5, True, {"table_size": 128})
    assert (
        w.quality.chooser.currentText() == "default" and "slicer (default)" in w.renderers.frame_label.text()
    )
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.renderers.switch("vtk")
    s = w.state.settings
    assert (w.state.renderer, s.step, s.preintegration, dict(s.options)) == ("vtk", 0.75, False, {})
    assert w.quality.chooser.currentText() == "default" and w.docks.sampling.step.spin.value() == 0.75
    assert "vtk (default)" in w.renderers.frame_label.text()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.renderers.switch("slicer")  # back at slicer's default, not at draft
    s = w.state.settings
    assert (s.step, s.preintegration, dict(s.options)) == (0.5, True, {"table_size": 128})
    assert w.quality.chooser.currentText() == "default"
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.renderers.switch("vtk")
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.state.set_settings(w.state.settings.with_(step=0.3))  # custom now
    assert "vtk (custom)" in w.renderers.frame_label.text()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.renderers.switch("slicer")
    s = w.state.settings
    assert (w.state.renderer, s.step, dict(s.options)) == ("slicer", 0.3, {})
    assert w.quality.chooser.currentText() == "custom"
    # a second volume keeps the level shown: draft for slicer stays draft
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.quality.chooser.activated.emit(w.quality.chooser.findText("draft"))
    w.files.apply_loaded(sample)  # the same scene again: nothing new to draw
    assert w.state.settings.step == 2.0 and w.quality.chooser.currentText() == "draft"


def test_previews_use_the_interactive_level_and_a_tf_drag_the_renderers_drag_options(
    make_window, fake_renderers, sample, qtbot, monkeypatch
):
    """Issue 22: previews draw with cheaper measured settings (the `interactive` level), and while
    a TF point is dragged with the renderer's `tf_drag_options` too; the still frame after the
    gesture has the user's level, and the frame label says the preview was cheaper."""
    table_256 = {"table_size": 256}
    use_levels(monkeypatch, {"fake_drag": {"default": level(0.25, options=table_256),
                                           "interactive": level(0.5, options=table_256)}})  # fmt: skip
    w = make_window()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS) as blocker:
        w.files.apply_loaded(sample, "fake_drag")
    assert blocker.args[0].settings.step == 0.25  # the app opens at the default level

    labels = []

    def gesture(change):
        previews = []
        w.frameShown.connect(lambda f: previews.append(f) if not f.full else None)
        w.state.begin_interaction()
        change()
        qtbot.waitUntil(lambda: bool(previews), timeout=FRAME_TIMEOUT_MS)
        labels.append(w.renderers.frame_label.text())
        with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS) as still:
            w.state.end_interaction()
        return previews[0].settings, still.args[0].settings

    preview, still = gesture(lambda: w.state.set_camera(w.state.camera.azimuth(5.0)))
    assert "preview at lower quality" in labels[-1]
    assert (preview.step, dict(preview.options)) == (0.5, {"table_size": 256})
    assert (still.step, dict(still.options)) == (0.25, {"table_size": 256})
    tf = w.state.transfer_function
    points = tf.opacity_points.copy()
    points[-1, 1] *= 0.5
    preview, still = gesture(lambda: tf.set_opacity_points(points))
    assert (preview.step, dict(preview.options)) == (0.5, {"table_size": 8})
    assert (still.step, dict(still.options)) == (0.25, {"table_size": 256})
    # custom settings are previewed as they are, apart from the drag options
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.state.set_settings(w.state.settings.with_(step=0.3))
    preview, _ = gesture(lambda: w.state.set_camera(w.state.camera.azimuth(5.0)))
    assert (preview.step, dict(preview.options)) == (0.3, {"table_size": 256})
    assert "preview" in labels[-1] and "lower quality" not in labels[-1]


def test_a_slow_still_frame_is_refined_from_a_coarse_frame_of_the_whole_view(
    make_window, fake_renderers, sample, qtbot, monkeypatch
):
    """Issue 22, progressive refinement: when the still frame is measured slow and the preview
    settings are at most half its cost, the whole view comes first at the preview settings, then
    the still frame; one that is cheap comes alone, and so does one whose coarse frame would itself
    take seconds."""
    from volren.app.rendering.render_service import Frame

    table_256 = {"table_size": 256}
    use_levels(monkeypatch, {"fake_drag": {"default": level(0.25, options=table_256),
                                           "interactive": level(0.5, options=table_256)}})  # fmt: skip
    w = make_window()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.files.apply_loaded(sample, "fake_drag")  # at the default level
    assert w.quality.chooser.currentText() == "default"
    frames = []
    w.frameShown.connect(frames.append)
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.state.set_camera(w.state.camera.azimuth(5.0))  # measured cheap: no refinement
    assert [f.full for f in frames] == [True]

    width, height = w.viewport.pixel_size()
    still, coarse = w.state.settings, w.scheduler.preview()[1]

    def measured(still_ms: float, coarse_ms: float) -> None:
        """What the scheduler has measured, as if the still and the coarse frames took that long."""
        w.scheduler._costs.clear()  # forget the fake renderer's real (instant) frames
        for settings, ms in ((still, still_ms), (coarse, coarse_ms)):
            w.scheduler.note_frame(Frame(0, "fake_drag", width, height, ms, True, np.zeros((1, 1, 3), np.uint8),
                                         w.state.camera, settings))  # fmt: skip

    measured(900.0, 200.0)
    frames.clear()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.state.set_camera(w.state.camera.azimuth(5.0))
    assert [(f.full, (f.width, f.height), f.settings.step) for f in frames] == [
        (False, (width, height), 0.5), (True, (width, height), 0.25)]  # fmt: skip
    assert frames[1].camera == frames[0].camera == w.state.camera

    measured(14000.0, 8000.0)  # a coarse frame of seconds would only delay the still frame: it comes alone
    frames.clear()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.state.set_camera(w.state.camera.azimuth(5.0))
    assert [f.full for f in frames] == [True]


def test_frames_with_a_new_tf_size_the_tf_drags_previews_only(make_window, fake_renderers, sample, qtbot):
    """A frame with a new TF also pays for what the renderer keeps per TF (raycast's step choice):
    such frames size a TF drag's previews, and a rotation's only until frames without a new TF
    are measured (sized from TF edits' frames, bonsai's rotation previews were 17 % of the pixels
    at 18 fps)."""
    from volren.app.rendering.render_service import Frame

    w = make_window()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.files.apply_loaded(sample, "fake")
    width, height = w.viewport.pixel_size()
    preview = w.scheduler.preview(tf_dragged=False)
    w.scheduler._costs.clear()  # forget the fake renderer's real (instant) frames

    def note(ms: float, tf_changed: bool) -> None:
        w.scheduler.note_frame(Frame(0, preview[0], width, height, ms, True, np.zeros((1, 1, 3), np.uint8),
                                     w.state.camera, preview[1], False, tf_changed))  # fmt: skip

    budget = w.scheduler.preview_budget_ms
    note(400.0 * budget, True)  # a TF edit's frame: 400x the budget, 1 % of the pixels would be 4x
    assert w.scheduler.current_preview_scale(preview) == pytest.approx(0.1)  # none without a new TF yet
    note(0.5 * budget, False)  # a rotation's frame: within the budget at full size
    assert w.scheduler.current_preview_scale(preview) == w.scheduler.preview_scale
    w.scheduler._tf_dragged = True
    assert w.scheduler.current_preview_scale(preview) == pytest.approx(0.1)


def test_first_previews_at_new_settings_are_sized_from_the_renderers_other_frames(make_window, fake_renderers,
                                                                                   sample, qtbot):  # fmt: skip
    """A renderer that draws previews at settings it has drawn no frame at yet (raycast's first 2D
    previews) sizes them from its frames at other settings of the same TF dimension (its still
    frames), not at a quarter of the pixels for want of a cost."""
    from volren.app.rendering.render_service import Frame

    w = make_window()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.files.apply_loaded(sample, "fake")
    width, height = w.viewport.pixel_size()
    preview = w.scheduler.preview(tf_dragged=False)
    finer = preview[1].with_(step=preview[1].step / 2)  # the still frames' settings, in effect
    w.scheduler._costs.clear()  # forget the fake renderer's real (instant) frames
    assert w.scheduler.current_preview_scale(preview) == w.scheduler.preview_scale  # nothing measured
    budget = w.scheduler.preview_budget_ms
    w.scheduler.note_frame(Frame(0, preview[0], width, height, 100.0 * budget, True, np.zeros((1, 1, 3), np.uint8),
                                 w.state.camera, finer))  # fmt: skip
    assert w.scheduler.current_preview_scale(preview) == pytest.approx(0.1)  # 1 % of the pixels: the budget


def window_previewing_with(make_window, monkeypatch, qtbot, sample, preview: str):
    """A window showing `fake_drag`'s still frame of `sample`, with `preview` measured faster than
    `fake_drag` at `interactive` (so it draws the previews while it can)."""
    use_levels(monkeypatch, {"fake_drag": {"interactive": level(0.5, ms=50.0)},
                             preview: {"interactive": level(1.0, ms=5.0)}})  # fmt: skip
    w = make_window()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.files.apply_loaded(sample, "fake_drag")
    return w


def test_previews_are_drawn_by_the_fastest_measured_renderer_and_the_label_says_so(
    make_window, fake_renderers, sample, qtbot, monkeypatch
):
    """Issue 22: "the fastest renderer for previews and the chosen one for the still frame, saying
    so": with `fake` measured faster at `interactive`, a rotation of a `fake_drag` scene at a level
    previews with `fake` (named in the frame label) and ends with `fake_drag`'s still frame."""
    w = window_previewing_with(make_window, monkeypatch, qtbot, sample, "fake")
    frames, labels = [], []
    w.frameShown.connect(lambda f: (frames.append(f), labels.append(w.renderers.frame_label.text())))
    w.state.begin_interaction()
    w.state.set_camera(w.state.camera.azimuth(5.0))
    qtbot.waitUntil(lambda: bool(frames), timeout=FRAME_TIMEOUT_MS)
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS) as still:
        w.state.end_interaction()
    assert (frames[0].full, frames[0].renderer, frames[0].settings.step) == (False, "fake", 1.0)
    assert labels[0].startswith("fake (interactive)  |") and "preview" in labels[0]
    assert (still.args[0].renderer, still.args[0].settings.step) == ("fake_drag", 0.5)
    assert w.state.renderer == "fake_drag"


def test_the_preview_renderer_is_set_up_while_the_view_is_still(make_window, fake_renderers, sample, qtbot,
                                                                 monkeypatch):  # fmt: skip
    """The first preview of a drag paid the preview renderer's set-up (shearwarp: 0.7 s on bonsai,
    the first drag showed nothing for that long): after a still frame the previews' renderer is
    set up with a tiny frame nobody sees, so the first preview pays nothing."""
    use_levels(monkeypatch, {"fake_drag": {"interactive": level(0.5, ms=50.0)},
                             "fake": {"interactive": level(1.0, ms=5.0)}})  # fmt: skip
    calls = fake_renderers["fake"].calls
    w = make_window()
    shown = []
    w.frameShown.connect(shown.append)
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS) as still:
        w.files.apply_loaded(sample, "fake_drag")
    qtbot.waitUntil(lambda: any(c["size"] == (8, 8) for c in calls), timeout=FRAME_TIMEOUT_MS)
    qtbot.waitUntil(lambda: not w.service.warming, timeout=FRAME_TIMEOUT_MS)
    assert [f.renderer for f in shown] == ["fake_drag"]  # the warm-up is not shown
    assert w.service.latest_serial == still.args[0].serial  # nor does it stand for the newest frame
    w.state.begin_interaction()
    w.state.set_camera(w.state.camera.azimuth(5.0))
    qtbot.waitUntil(lambda: len(shown) > 1, timeout=FRAME_TIMEOUT_MS)
    w.state.end_interaction()
    assert shown[1].renderer == "fake" and not shown[1].setup  # set up already
    assert sum(c["size"] == (8, 8) for c in calls) == 1


def test_a_preview_renderer_that_fails_previews_no_more_and_the_still_frame_comes(
    make_window, fake_renderers, sample, qtbot, monkeypatch, error_boxes
):
    w = window_previewing_with(make_window, monkeypatch, qtbot, sample, "fake_broken")
    w.state.begin_interaction()
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS) as still:
        w.state.set_camera(
            w.state.camera.azimuth(5.0)
        )  # fake_broken's preview fails: the still frame follows
    assert still.args[0].renderer == "fake_drag" and still.args[0].camera == w.state.camera
    frames = []
    w.frameShown.connect(frames.append)
    w.state.set_camera(w.state.camera.azimuth(5.0))
    qtbot.waitUntil(lambda: bool(frames), timeout=FRAME_TIMEOUT_MS)
    assert frames[0].renderer == "fake_drag" and not frames[0].full
    w.state.end_interaction()
    assert error_boxes == [] and w.state.renderer == "fake_drag"


def test_a_preview_renderer_that_cannot_draw_the_view_is_passed_over_only_while_it_cannot(
    make_window, fake_renderers, sample, qtbot, monkeypatch, error_boxes
):
    w = window_previewing_with(make_window, monkeypatch, qtbot, sample, "fake_outside_only")
    outside = w.state.camera
    inside = inside_camera(w.state.volume.bounds)
    frames = []
    w.frameShown.connect(frames.append)
    w.state.begin_interaction()
    w.state.set_camera(inside)
    qtbot.waitUntil(lambda: any(not f.full for f in frames), timeout=FRAME_TIMEOUT_MS)
    assert next(f for f in frames if not f.full).renderer == "fake_drag"  # the fast one refuses this view
    frames.clear()
    w.state.set_camera(outside.azimuth(5.0))
    qtbot.waitUntil(lambda: any(not f.full for f in frames), timeout=FRAME_TIMEOUT_MS)
    assert next(f for f in frames if not f.full).renderer == "fake_outside_only"  # and previews again outside
    w.state.end_interaction()
    assert error_boxes == [] and w.state.renderer == "fake_drag"
