"""A crop box drawn as a clip box by renderers that clip: the whole volume stays prepared while a
face is dragged, the cut is exact, and renderers that do not clip still get the cut volume."""

from __future__ import annotations

import numpy as np
import pytest

from tests.app.conftest import FRAME_TIMEOUT_MS
from volren.app.core.state import ViewState, default_camera
from volren.model import RenderSettings
from volren.model.clip_region import ClipPlane, ClipRegion
from volren.model.volume import TetVolume
from volren.samples import marschner_lobb, sample_transfer_functions
from volren.testing.scenes import lattice_volume

BOX = (-1.0, 0.1, -1.0, 1.0, -0.5, 1.0)


def _state(renderer: str, volume=None) -> ViewState:
    s = ViewState(renderer)
    volume = volume if volume is not None else marschner_lobb(9)
    s.load(volume, sample_transfer_functions()["marschner_lobb"], default_camera(volume))
    return s


def test_a_renderer_that_clips_gets_the_whole_volume_and_the_box_as_its_clip_box():
    s = _state("raycast")
    planes = RenderSettings(clip=ClipRegion((ClipPlane((0, 0, 0), (1, 1, 0)),)))
    s.set_settings(planes)
    s.set_crop(BOX)
    volume, settings = s.frame_inputs("raycast", s.settings)
    assert volume is s.volume
    assert settings.clip == ClipRegion(planes.clip.planes, BOX)  # the oblique planes kept
    assert s.shown_bounds == BOX
    volume, settings = s.frame_inputs("example", s.settings)  # does not clip: the cut volume
    assert volume is s.render_volume and volume.dimensions == (6, 9, 7)  # snapped out to samples
    assert settings.clip.box is None


def test_a_mesh_crop_cuts_no_cells_on_the_gui_thread_for_a_renderer_that_clips(monkeypatch):
    """Cutting a mesh to whole cells took up to 0.49 s per step of a face drag on oxygen."""
    import volren.app.core.state as state_module

    mesh = lattice_volume("tet", lambda x, y, z: x + y, (6, 6, 6))
    assert isinstance(mesh, TetVolume)
    s = _state("tetra", mesh)

    def no_cutting(*args):
        raise AssertionError("the mesh was cut on the GUI thread")

    monkeypatch.setattr(state_module, "crop_volume", no_cutting)
    for xmax in (4.0, 3.2, 2.7):  # 2.7 keeps no whole cell of the last column: exact, not refused
        s.set_crop((0.0, xmax, 0.0, 5.0, 0.0, 5.0))
        volume, settings = s.frame_inputs("tetra", s.settings)
        assert volume is mesh and settings.clip.box == (0.0, xmax, 0.0, 5.0, 0.0, 5.0)


def test_a_crop_face_drag_keeps_the_renderers_volume_and_ends_on_the_exact_cut(make_window, sample, qtbot,
                                                                               monkeypatch):  # fmt: skip
    """Each step of a crop-face drag rebuilt the volume and made the renderer prepare it again:
    1 preview/s on bonsai, none on oxygen. Now every frame of the drag, previews included, is
    drawn from the volume loaded, the box given as the clip box."""
    window = make_window()
    with qtbot.waitSignal(window.fullFrameShown, timeout=FRAME_TIMEOUT_MS) as first:
        window.files.apply_loaded(sample, "raycast")
    qtbot.waitUntil(lambda: not window.service.warming, timeout=FRAME_TIMEOUT_MS)
    state = window.state
    submitted: list[tuple[str, object, tuple | None]] = []
    submit = window.service.submit

    def recording(renderer, volume, tf, settings, *args, **kwargs):
        submitted.append((renderer, volume, settings.clip.box))
        return submit(renderer, volume, tf, settings, *args, **kwargs)

    monkeypatch.setattr(window.service, "submit", recording)
    bounds = state.volume.bounds
    state.begin_interaction()
    for xmax in (0.8, 0.5, 0.2):
        state.set_crop((bounds[0], xmax, *bounds[2:]))
        qtbot.wait(30)
    with qtbot.waitSignal(window.fullFrameShown, timeout=FRAME_TIMEOUT_MS) as shown:
        state.end_interaction()
    assert submitted and all(volume is state.volume for _, volume, _ in submitted)
    assert all(box is not None and box[1] in (0.8, 0.5, 0.2) for _, _, box in submitted)
    frame = shown.args[0]
    assert frame.full and frame.volume is state.volume
    assert frame.settings.clip.box == (bounds[0], 0.2, *bounds[2:])
    uncut = first.args[0].rgb.astype(int)
    assert np.abs(frame.rgb.astype(int) - uncut).mean() > 2  # the cut shows


@pytest.mark.parametrize("xmax", [0.2])
def test_the_screenshot_of_a_clipped_view_draws_what_the_view_draws(xmax):
    from volren.app.files.screenshot import ScreenshotJob

    s = _state("raycast")
    s.set_crop((-1.0, xmax, -1.0, 1.0, -1.0, 1.0))
    job = ScreenshotJob.of_view(s, "x.png", 8, 8)
    assert job.volume is s.volume and job.settings.clip.box == (-1.0, xmax, -1.0, 1.0, -1.0, 1.0)
    assert job.bounds == (-1.0, xmax, -1.0, 1.0, -1.0, 1.0)
