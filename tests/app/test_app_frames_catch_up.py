"""The frame always catches up: whatever the order of Show array, crop, TF and camera changes, the
last frame on screen is the full frame of the current state (real widgets, offscreen)."""

from __future__ import annotations

import itertools
import time
from typing import ClassVar

import numpy as np
import pytest
from PyQt5.QtCore import QPoint, Qt

from volren.app.rendering.scheduling import FrameScheduler
from volren.model.scene_class import SceneClass
from volren.quality import Measurement, QualityTable
from volren.renderers.base import QualityLevel


def measured(
    label: str, step: float, pre: bool, options: dict, ms: dict, worst: float, meets: bool = True
) -> Measurement:
    """A measured level whose peer took 1 ms on every scene (ratios rank as frame times)."""
    return Measurement(QualityLevel(label, step, pre, options), ms, dict.fromkeys(ms, 1.0), worst, meets)


pytestmark = [pytest.mark.qt]

TIMEOUT_MS = 20000


def levels_for(renderer: str, monkeypatch) -> None:
    """A measured table where `renderer`'s still frames (default) differ from its previews
    (interactive), so a still frame can follow a coarse one (progressive refinement)."""
    from volren import quality

    def level(step: float) -> Measurement:
        return measured(f"step {step}", step, False, {"table_size": 256}, {"a/smooth": 10.0}, 1.0)

    table = QualityTable(
        {SceneClass("uniform"): {renderer: {"default": level(0.25), "interactive": level(0.5)}}}, {}
    )
    monkeypatch.setattr(quality, "table", lambda: table)


@pytest.fixture
def slow_fake(fake_renderers):
    """The drag-options fake, taking 20 ms a frame, so requests overtake frames as in real use."""
    from volren.renderers.registry import registry

    class SlowFrames(fake_renderers["fake_drag"]):
        name: ClassVar[str] = "fake_slow_frames"

        def _render(self, camera, width, height, progress):
            time.sleep(0.02)
            return super()._render(camera, width, height, progress)

    registry.register(SlowFrames.name, SlowFrames, replace=True)
    try:
        yield SlowFrames.name
    finally:
        registry.unregister(SlowFrames.name)


def two_field_file(tmp_path):
    import pyvista as pv

    grid = pv.ImageData(dimensions=(9, 8, 7), spacing=(1.0, 0.5, 2.0))
    rng = np.random.default_rng(3)
    grid.point_data["density"] = rng.uniform(0, 10, grid.n_points).astype(np.float32)
    grid.point_data["pressure"] = rng.uniform(-1, 1, grid.n_points).astype(np.float32)
    path = tmp_path / "two.vti"
    grid.save(path)
    return path


def current(w) -> bool:
    """Whether the frame on screen is the full frame of the state as it is now."""
    s, frame = w.state, w.viewport.frame
    tf = s.transfer_function
    shown = w.frames_shown[-1] if w.frames_shown else None
    return (frame is not None and shown is not None and shown.full and shown.renderer == s.renderer
            and shown.volume is s.render_volume and shown.tf_key == (id(tf), tf.version)
            and shown.camera == s.camera and shown.serial == w.service.latest_serial)  # fmt: skip


def caught_up(w, qtbot) -> None:
    """Wait until the state's full frame is on screen, then check that nothing replaces it."""
    qtbot.waitUntil(lambda: not w.files.loader.busy and current(w), timeout=TIMEOUT_MS)
    shown = len(w.frames_shown)
    qtbot.wait(300)
    assert len(w.frames_shown) == shown and current(w)


def test_a_refinement_asked_twice_still_ends_in_its_still_frame(
    make_window, slow_fake, sample, qtbot, monkeypatch
):
    """A request for the same full frame while its coarse frame is drawn (Show array sets the
    background and crop after the volume) dropped the refinement: the coarse frame stayed on
    screen until the next gesture."""
    levels_for(slow_fake, monkeypatch)
    monkeypatch.setattr(FrameScheduler, "_worth_refining", lambda *args: True)
    w = make_window()
    w.frames_shown = []
    w.frameShown.connect(w.frames_shown.append)
    with qtbot.waitSignal(w.fullFrameShown, timeout=TIMEOUT_MS):
        w.files.apply_loaded(sample, slow_fake)
    w.state.set_camera(w.state.camera.azimuth(10.0))  # a coarse frame, then the still frame
    w.state.set_background(w.state.background)  # the same full frame asked again
    caught_up(w, qtbot)
    assert [f.full for f in w.frames_shown[-2:]] == [False, True]


def test_show_array_with_a_crop_draws_no_uncropped_frame(make_window, fake_renderers, qtbot, tmp_path, ini):
    """Show array brought the new field's volume uncropped first (the crop came a change later)."""
    w = make_window(settings=ini)
    frames = []
    w.frameShown.connect(frames.append)
    with qtbot.waitSignal(w.fullFrameShown, timeout=TIMEOUT_MS):
        w.files.open_input(two_field_file(tmp_path), renderer="fake")
    w.docks.crop.enable.setChecked(True)
    w.docks.crop.spins[1].setValue(4.0)  # xmax: half the volume
    box = w.state.crop
    assert box is not None
    frames.clear()
    with qtbot.waitSignal(w.files.loadFinished, timeout=TIMEOUT_MS):
        w.files.show_array("pressure")
    qtbot.waitUntil(lambda: bool(frames) and frames[-1].full, timeout=TIMEOUT_MS)
    assert w.state.volume.scalars == "pressure" and w.state.crop == box
    assert all(f.volume.bounds[1] == pytest.approx(4.0) for f in frames), [f.volume.bounds for f in frames]


ACTIONS = ("array", "crop", "tf", "camera")


def test_the_last_frame_is_the_current_states_full_frame_in_every_order(make_window, slow_fake, qtbot, tmp_path,
                                                                         monkeypatch, ini):  # fmt: skip
    """Show array, a crop-box edit, a TF edit and a rotation by mouse, back to back in each of the
    24 orders, with progressive refinement on every still frame: the frame left on screen is the
    full frame of the resulting state."""
    levels_for(slow_fake, monkeypatch)
    monkeypatch.setattr(FrameScheduler, "_worth_refining", lambda *args: True)
    w = make_window(settings=ini)
    w.frames_shown = []
    w.frameShown.connect(w.frames_shown.append)
    with qtbot.waitSignal(w.fullFrameShown, timeout=TIMEOUT_MS):
        w.files.open_input(two_field_file(tmp_path), renderer=slow_fake)
    fields = iter(itertools.cycle(["pressure", "density"]))
    crop = w.docks.crop
    crop.enable.setChecked(True)
    caught_up(w, qtbot)

    def act(name: str, turn: int) -> None:
        if name == "array":
            box = w.docks.dataset.array_box
            index = box.findText(next(fields))
            box.setCurrentIndex(index)
            box.activated.emit(index)
        elif name == "crop":
            crop.spins[1].setValue(3.0 + turn % 4)  # xmax
        elif name == "tf":
            tf = w.state.transfer_function
            points = tf.opacity_points.copy()
            points[:, 1] = np.clip(points[:, 1] * (0.9 if turn % 2 else 1.1), 0.0, 1.0)
            tf.set_opacity_points(points)
        else:
            window = w.windowHandle()
            c = w.viewport.mapTo(w, w.viewport.rect().center())
            qtbot.mousePress(window, Qt.LeftButton, pos=c)
            for i in range(1, 4):
                qtbot.mouseMove(window, c + QPoint(6 * i, 2 * i))
            qtbot.mouseRelease(window, Qt.LeftButton, pos=c + QPoint(18, 6))

    for turn, order in enumerate(itertools.permutations(ACTIONS)):
        for name in order:
            act(name, turn)
        caught_up(w, qtbot)
