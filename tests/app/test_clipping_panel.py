"""The clipping panel edits the planes in the state's settings: add, switch off, invert, presets,
the point and normal, and the position slider as a gesture."""

from __future__ import annotations

import numpy as np
import pytest
from PyQt5.QtCore import Qt

from tests.app.conftest import FRAME_TIMEOUT_MS
from volren.app.core.plane_handles import extent_along
from volren.app.core.state import Change
from volren.app.panels.clipping import POSITION_TICKS, ClippingPanel
from volren.model.clip_region import MAX_PLANES, ClipPlane
from volren.renderers.registry import registry


@pytest.fixture
def panel(qtbot, state):
    widget = ClippingPanel(state)
    qtbot.addWidget(widget)
    return widget


def test_add_puts_a_plane_through_the_centre_facing_away_from_the_eye(panel, state):
    assert not panel.remove_button.isEnabled()
    panel.add_plane()
    (plane,) = state.settings.clip.planes
    lo, hi = np.asarray(state.volume.bounds[0::2]), np.asarray(state.volume.bounds[1::2])
    assert np.allclose(plane.origin, (lo + hi) / 2)
    assert np.allclose(plane.normal, state.camera.direction)
    assert panel.plane_list.count() == 1 and panel.selected() == 0 and panel.remove_button.isEnabled()


def test_switching_a_plane_off_keeps_it_and_clips_nothing(panel, state):
    panel.add_plane()
    panel.plane_list.item(0).setCheckState(Qt.Unchecked)
    (plane,) = state.settings.clip.planes
    assert not plane.enabled and state.settings.clip.is_empty
    panel.plane_list.item(0).setCheckState(Qt.Checked)
    assert state.settings.clip.planes[0].enabled and not state.settings.clip.is_empty


def test_invert_presets_and_remove(panel, state):
    panel.add_plane()
    panel.invert_plane()
    assert state.settings.clip.planes[0].invert
    panel.axis_buttons["Y"].click()
    assert state.settings.clip.planes[0].normal == (0.0, 1.0, 0.0)
    assert "inverted" in panel.plane_list.item(0).text()
    panel.remove_plane()
    assert state.settings.clip.planes == () and panel.plane_list.count() == 0


def test_no_more_than_six_planes(panel, state):
    for _ in range(MAX_PLANES + 2):
        panel.add_plane()
    assert len(state.settings.clip.planes) == MAX_PLANES and not panel.add_button.isEnabled()


def test_the_point_and_normal_fields_edit_the_selected_plane_and_a_zero_normal_is_ignored(panel, state):
    panel.add_plane()
    panel.spins[0].setValue(0.25)  # point x
    assert state.settings.clip.planes[0].origin[0] == 0.25
    for spin in panel.spins[3:]:
        spin.setValue(0.0)
    normal = state.settings.clip.planes[0].normal
    assert np.linalg.norm(normal) > 0


def test_the_position_slider_moves_the_plane_along_its_normal_as_one_gesture(panel, state):
    panel.add_plane()
    panel.axis_buttons["X"].click()
    changes: list[Change] = []
    state.subscribe(changes.append)
    panel.position.sliderPressed.emit()
    for tick in (600, 500, 250):
        panel.position.setValue(tick)
    panel.position.sliderReleased.emit()
    lo, hi = extent_along(state.volume.bounds, (1.0, 0.0, 0.0))
    assert state.settings.clip.planes[0].origin[0] == pytest.approx(lo + 0.25 * (hi - lo))
    assert [c.interactive for c in changes if c.what == "settings"] == [True, True, True]
    assert changes[-1] == Change("interaction", False)  # the full frame follows the release
    assert panel.position.value() == round(0.25 * POSITION_TICKS)


def test_a_plane_added_under_a_renderer_that_cannot_clip_switches_to_one_that_can(
    make_window, fake_renderers, sample, qtbot
):
    window = make_window()
    with qtbot.waitSignal(window.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        window.files.apply_loaded(sample, "fake")
    assert not registry.capabilities("fake").kinds["uniform"].clip_region
    with qtbot.waitSignal(window.fullFrameShown, timeout=FRAME_TIMEOUT_MS) as shown:
        window.docks.clipping.add_plane()
    state = window.state
    assert registry.capabilities(state.renderer).kinds["uniform"].clip_region
    assert shown.args[0].renderer == state.renderer
    assert shown.args[0].settings.clip.planes == state.settings.clip.planes
    assert isinstance(state.settings.clip.planes[0], ClipPlane)


def test_the_cut_faces_box_sets_the_cap_and_plane_edits_keep_it(panel, state):
    panel.add_plane()
    panel.cap.setChecked(True)
    assert state.settings.clip.cap and state.settings.clip.caps
    panel.invert_plane()
    assert state.settings.clip.cap
    panel.cap.setChecked(False)
    assert not state.settings.clip.cap
