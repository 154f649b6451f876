"""The render thread: renderer confined to one worker thread, newest request only, failures reported."""

from __future__ import annotations

import threading
import time
from typing import ClassVar

import numpy as np
import pytest

from volren.app.rendering.render_service import RenderService
from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.settings import RenderSettings
from volren.renderers.base import Capabilities, KindSupport, RendererBase
from volren.samples import marschner_lobb, sample_transfer_functions

pytestmark = pytest.mark.qt


class SlowRenderer(RendererBase):
    """Takes 60 ms a frame, reports progress, and records the thread of every call."""

    name: ClassVar[str] = "slow"
    capabilities: ClassVar[Capabilities] = Capabilities(kinds={"uniform": KindSupport()})
    log: ClassVar[list[tuple[str, int]]] = []

    def __init__(self) -> None:
        super().__init__()
        self.log.append(("create", threading.get_ident()))

    def set_volume(self, volume) -> None:
        self.log.append(("volume", threading.get_ident()))
        super().set_volume(volume)

    def set_transfer_function(self, tf) -> None:
        self.log.append(("tf", threading.get_ident()))
        super().set_transfer_function(tf)

    def _render(self, camera, width, height, progress):
        self.log.append(("render", threading.get_ident()))
        for i in range(6):
            time.sleep(0.01)
            if progress is not None:
                progress(i / 6)
        return np.full((height, width, 4), 0.5, np.float32), {}

    def release(self) -> None:
        self.log.append(("release", threading.get_ident()))
        super().release()


class FailingRenderer(SlowRenderer):
    def _render(self, camera, width, height, progress):
        raise VolrenError("out of\nmemory")


@pytest.fixture
def scene():
    volume = marschner_lobb(9)
    return volume, sample_transfer_functions()["marschner_lobb"], Camera.orbit(volume.bounds)


def test_newest_request_wins_and_the_renderer_stays_on_one_thread(qtbot, scene):
    SlowRenderer.log.clear()
    service = RenderService(factory=lambda name: SlowRenderer())
    volume, tf, camera = scene
    frames = []
    service.frameReady.connect(frames.append)
    try:
        with qtbot.waitSignal(service.frameReady, timeout=5000):
            service.submit("slow", volume, tf, RenderSettings(), camera, 8, 8)
        frames.clear()
        serials = [
            service.submit("slow", volume, tf, RenderSettings(), camera.azimuth(i), 8, 8, full=False)
            for i in range(20)
        ]
        qtbot.waitUntil(lambda: bool(frames) and frames[-1].serial == serials[-1], timeout=5000)
    finally:
        service.shutdown()
    assert len(frames) < len(serials), "stale requests were not dropped"
    assert frames[-1].camera == camera.azimuth(19) and not frames[-1].full
    assert frames[-1].rgb.shape == (8, 8, 3) and frames[-1].rgb.dtype == np.uint8
    threads = {ident for _, ident in SlowRenderer.log}
    assert len(threads) == 1 and threading.get_ident() not in threads
    kinds = [k for k, _ in SlowRenderer.log]
    assert kinds[0] == "create" and kinds[-1] == "release"
    assert kinds.count("volume") == 1 and kinds.count("tf") == 1, "unchanged inputs were sent again"


def _previews_shown_during_a_drag(qtbot, scene, requests: int) -> int:
    """Preview requests every 10 ms to `SlowRenderer` (60 ms a frame): the frames shown meanwhile."""
    service = RenderService(factory=lambda name: SlowRenderer())
    volume, tf, camera = scene
    frames = []
    service.frameReady.connect(frames.append)
    try:
        for i in range(requests):
            service.submit("slow", volume, tf, RenderSettings(), camera.azimuth(i), 8, 8, full=False)
            qtbot.wait(10)
        return len(frames)
    finally:
        service.shutdown()


def test_a_continuous_drag_still_shows_frames(qtbot, scene):
    """Requests every 10 ms, frames of 60 ms: each frame finishes and is shown (a newer request
    waiting must not abandon a short frame, or a drag would show nothing until it stops)."""
    shown_during_drag = _previews_shown_during_a_drag(qtbot, scene, 60)
    assert shown_during_drag >= 4, f"only {shown_during_drag} frames shown during a 0.6 s drag"


@pytest.mark.parametrize("first_full", [True, False], ids=["full frame", "preview"])
def test_a_long_frame_gives_way_to_a_newer_full_frame(qtbot, scene, monkeypatch, first_full):
    """A full frame or a preview that runs long is abandoned for the full frame asked for after it
    (a release's): only the newer one is shown."""
    import volren.app.rendering.render_service as rs

    monkeypatch.setattr(rs, "INTERRUPT_AFTER_S", 0.02)  # the 60 ms frame counts as long
    service = RenderService(factory=lambda name: SlowRenderer())
    volume, tf, camera = scene
    frames = []
    service.frameReady.connect(frames.append)
    try:
        first = service.submit("slow", volume, tf, RenderSettings(), camera, 8, 8, full=first_full)
        qtbot.wait(35)  # the first frame is running, past the threshold
        second = service.submit("slow", volume, tf, RenderSettings(), camera.azimuth(5), 8, 8, full=True)
        qtbot.waitUntil(lambda: any(f.serial == second for f in frames), timeout=5000)
    finally:
        service.shutdown()
    assert [f.serial for f in frames] == [second], f"frame {first} was finished although superseded"


def test_a_long_preview_is_shown_although_newer_previews_wait(qtbot, scene, monkeypatch):
    """Previews slower than the requests of a drag (a 2D TF's): each one is finished and shown, not
    abandoned for the next preview, or the drag shows nothing and the cost model never learns."""
    import volren.app.rendering.render_service as rs

    monkeypatch.setattr(rs, "INTERRUPT_AFTER_S", 0.02)  # every 60 ms frame counts as long
    shown_during_drag = _previews_shown_during_a_drag(qtbot, scene, 30)
    assert shown_during_drag >= 2, f"only {shown_during_drag} previews shown during a 0.3 s drag"


def test_slow_frames_report_progress(qtbot, scene, monkeypatch):
    import volren.app.rendering.render_service as rs

    monkeypatch.setattr(rs, "PROGRESS_INTERVAL_S", 0.0)
    service = RenderService(factory=lambda name: SlowRenderer())
    volume, tf, camera = scene
    reports = []
    service.progressed.connect(lambda serial, name, fraction: reports.append((serial, name, fraction)))
    try:
        with qtbot.waitSignal(service.frameReady, timeout=5000):
            serial = service.submit("slow", volume, tf, RenderSettings(), camera, 4, 4)
    finally:
        service.shutdown()
    assert reports and all(r[:2] == (serial, "slow") for r in reports)
    assert [r[2] for r in reports] == sorted(r[2] for r in reports)


def test_a_tf_edit_reaches_the_renderer(qtbot, scene):
    SlowRenderer.log.clear()
    service = RenderService(factory=lambda name: SlowRenderer())
    volume, tf, camera = scene
    try:
        for _ in range(2):
            with qtbot.waitSignal(service.frameReady, timeout=5000):
                service.submit("slow", volume, tf, RenderSettings(), camera, 4, 4)
            tf.set_opacity_unit_distance(0.3)
    finally:
        service.shutdown()
    assert [k for k, _ in SlowRenderer.log].count("tf") == 2


def test_failures_come_back_as_one_line(qtbot, scene):
    service = RenderService(factory=lambda name: FailingRenderer())
    volume, tf, camera = scene
    try:
        with qtbot.waitSignal(service.renderFailed, timeout=5000) as blocker:
            serial = service.submit("failing", volume, tf, RenderSettings(), camera, 4, 4)
    finally:
        service.shutdown()
    request, message = blocker.args
    assert request.serial == serial and message == "out of memory"


def test_shutdown_is_idempotent_and_drops_requests(qtbot, scene):
    service = RenderService(factory=lambda name: SlowRenderer())
    volume, tf, camera = scene
    service.shutdown()
    service.shutdown()
    serial = service.submit("slow", volume, tf, RenderSettings(), camera, 4, 4)
    assert serial == 0
