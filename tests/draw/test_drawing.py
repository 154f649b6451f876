"""`volren.draw`: every path from a scene to pixels goes through it, and a kept `Drawing` prepares
its renderer once for many frames (counted in calls, not time)."""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from typing import ClassVar

import numpy as np
import pytest

import volren
from volren.cli.main import main
from volren.draw import Drawing, VolumeInput
from volren.draw import drawing as drawing_module
from volren.draw import frame as frame_module
from volren.errors import VolrenError
from volren.io import save_volume
from volren.model.animation import Animation
from volren.model.camera import Camera
from volren.model.scene import Scene
from volren.model.settings import RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import UniformVolume
from volren.renderers.base import Capabilities, FrameStats, KindSupport, RendererBase
from volren.renderers.registry import registry

NAME = "counting"


class CountingRenderer(RendererBase):
    """A renderer whose colour is its TF's opacity at the data's middle value, counting what it is
    given: set-ups of a volume, TFs, frames."""

    name: ClassVar[str] = NAME
    capabilities: ClassVar[Capabilities] = Capabilities(
        kinds={"uniform": KindSupport()}, summary="test double"
    )
    counts: ClassVar[dict[str, int]] = {}

    def _count(self, what: str) -> None:
        type(self).counts[what] = type(self).counts.get(what, 0) + 1

    def _volume_changed(self) -> None:
        self._count("volume")

    def _tf_changed(self) -> None:
        self._count("tf")

    def _render(self, camera, width, height, progress) -> tuple[np.ndarray, Mapping[str, float]]:
        self._count("frame")
        image = np.zeros((height, width, 4), np.float32)
        image[..., 3] = self.transfer_function.to_dict()["opacity"][-1][1]
        return image, {}


@pytest.fixture
def counting() -> Iterator[dict[str, int]]:
    CountingRenderer.counts.clear()
    registry.register(NAME, CountingRenderer, replace=True)
    try:
        yield CountingRenderer.counts
    finally:
        registry.unregister(NAME)


@pytest.fixture
def prepares(monkeypatch) -> list[str]:
    """The renderers `volren.draw` prepares, by name, in order."""
    made: list[str] = []
    original = drawing_module.prepare

    def spy(name, *args, **kwargs):
        made.append(name)
        return original(name, *args, **kwargs)

    monkeypatch.setattr(drawing_module, "prepare", spy)
    return made


@pytest.fixture
def frames(monkeypatch) -> list[tuple[int, int]]:
    """The sizes of the frames `volren.draw` draws whole (`render_frame`, the output checked)."""
    drawn: list[tuple[int, int]] = []
    original = frame_module.render_frame

    def spy(renderer, camera, width, height, *args, **kwargs):
        drawn.append((width, height))
        return original(renderer, camera, width, height, *args, **kwargs)

    monkeypatch.setattr(frame_module, "render_frame", spy)
    return drawn


def tf(opacity: float) -> TransferFunction1D:
    return TransferFunction1D.from_dict(
        {"color": [[0, 1, 1, 1], [4, 1, 1, 1]], "opacity": [[0, 0], [4, opacity]]}
    )


VOLUME = UniformVolume(np.arange(5 * 6 * 7, dtype=np.float32).reshape(5, 6, 7) % 5, (1.0, 1.0, 1.0))


def test_volren_render_goes_through_draw(counting, prepares, frames):
    image = volren.render(VOLUME, tf(0.25), renderer=NAME, size=(9, 7))
    assert prepares == [NAME] and frames == [(9, 7)]
    assert image.shape == (7, 9, 4) and float(image[0, 0, 3]) == 0.25


def test_volren_render_command_goes_through_draw(counting, prepares, frames, tmp_path, capsys):
    path = tmp_path / "v.vti"
    save_volume(VOLUME, path)
    assert (
        main(["render", str(path), "--renderer", NAME, "--size", "8x6", "-o", str(tmp_path / "o.png")]) == 0
    )
    assert prepares == [NAME] and frames == [(8, 6)]
    assert capsys.readouterr().out.startswith(f"{NAME}: 8x6 in ")


def test_volren_movie_prepares_once_and_draws_each_frame_through_draw(
    counting, prepares, frames, tmp_path, capsys
):
    path = tmp_path / "v.vti"
    save_volume(VOLUME, path)
    assert main(["movie", str(path), "--renderer", NAME, "--size", "8", "--frames", "3",
                 "-o", str(tmp_path / "m.gif")]) == 0  # fmt: skip
    assert prepares == [NAME] and frames == [(8, 8)] * 3
    assert counting["volume"] == 1


def test_the_apps_screenshot_and_movie_go_through_draw(counting, prepares, frames, tmp_path):
    pytest.importorskip("PyQt5")
    from volren.app.files.movie_export import MovieJob, record_job
    from volren.app.files.screenshot import ScreenshotJob, render_job

    job = ScreenshotJob(tmp_path / "s.png", 6, 4, NAME, VOLUME, tf(0.5), RenderSettings(), Camera.orbit(VOLUME.bounds),
                        (0.0, 0.0, 0.0), VOLUME.bounds)  # fmt: skip
    image = render_job(job)
    assert prepares == [NAME] and frames == [(6, 4)] and float(image[0, 0, 3]) == 0.5
    movie = ScreenshotJob(tmp_path / "m.gif", 6, 4, NAME, VOLUME, tf(0.5), RenderSettings(),
                          Camera.orbit(VOLUME.bounds), (0.0, 0.0, 0.0), VOLUME.bounds)  # fmt: skip
    record_job(MovieJob(movie, Animation(frames=2)))
    assert prepares == [NAME, NAME] and frames == [(6, 4)] * 3


def test_a_kept_drawing_prepares_once_for_new_cameras_and_tf_edits(counting, prepares, frames):
    with volren.drawing(VOLUME, tf(0.25), renderer=NAME, size=(5, 5)) as d:
        first = [d.frame(d.orbit(azimuth=a)).image for a in (0, 90, 180)]
        d.set_transfer_function(tf(0.75))
        edited = d.frame(d.orbit(elevation=30)).image
    assert prepares == [NAME] and counting["volume"] == 1 and counting["frame"] == 4
    assert counting["tf"] == 2  # the scene's, then the edit: only the TF is set again
    assert [float(i[0, 0, 3]) for i in first] == [0.25] * 3 and float(edited[0, 0, 3]) == 0.75


def test_a_kept_drawing_gives_what_single_renders_give(counting):
    with volren.drawing(VOLUME, tf(0.25), renderer=NAME, size=(5, 4)) as d:
        kept = d.frame(d.orbit(azimuth=40, zoom=1.5)).image
    np.testing.assert_array_equal(kept, volren.render(VOLUME, tf(0.25), renderer=NAME, size=(5, 4), azimuth=40,
                                                      zoom=1.5))  # fmt: skip


def test_a_drawing_outside_a_with_block_releases_its_renderer_after_each_frame(
    counting, prepares, monkeypatch
):
    released: list[str] = []
    monkeypatch.setattr(CountingRenderer, "release", lambda self: released.append(self.name), raising=False)
    scene = Scene(None, tf(0.5), Camera.orbit(VOLUME.bounds), renderer=NAME, size=(4, 4), volume=VOLUME)
    single = Drawing(VolumeInput(VOLUME), scene)
    single.frame()
    single.frame()
    assert prepares == [NAME, NAME] and released == [NAME, NAME]
    with pytest.raises(RuntimeError, match="with block"):
        single.renderer  # noqa: B018 - a renderer is kept only inside a with block


def test_a_frame_that_breaks_the_contract_is_refused_on_every_path(counting, monkeypatch):
    """The screenshot once took `renderer.render` as it came; every path now checks the frame."""
    pytest.importorskip("PyQt5")
    from volren.app.files.screenshot import ScreenshotJob, render_job

    def float64_frame(self, camera, width, height, progress=None):
        self.last_frame = FrameStats(1.0, width, height, {})
        return np.zeros((height, width, 4))

    monkeypatch.setattr(CountingRenderer, "render", float64_frame)
    job = ScreenshotJob("s.png", 6, 4, NAME, VOLUME, tf(0.5), RenderSettings(), Camera.orbit(VOLUME.bounds),
                        (0.0, 0.0, 0.0), VOLUME.bounds)  # fmt: skip
    with pytest.raises(VolrenError, match=f"renderer {NAME} returned float64"):
        render_job(job)
    with pytest.raises(VolrenError, match=f"renderer {NAME} returned float64"):
        volren.render(VOLUME, tf(0.5), renderer=NAME, size=(6, 4))
