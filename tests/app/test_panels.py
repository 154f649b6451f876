"""The settings panels: each edit changes exactly its field of the state, state changes from
elsewhere show without echoing back, held controls make one interaction, crop boxes, background
colour, dataset facts and renderer capabilities."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from PyQt5 import sip
from PyQt5.QtCore import QPoint, QPointF, Qt
from PyQt5.QtGui import QColor, QWheelEvent
from PyQt5.QtWidgets import QApplication, QStyle, QStyleOptionSpinBox

from volren.app.core.state import Change, ViewState, default_camera
from volren.app.panels import (
    BackgroundPanel,
    BlendPanel,
    CropPanel,
    DatasetInfoPanel,
    LightingPanel,
    SamplingPanel,
)
from volren.app.panels.controls import GestureSpinBox
from volren.app.panels.crop import decimals_for
from volren.model.settings import BlendMode, RenderSettings
from volren.model.tet_repair import repair_tets
from volren.model.transfer_function_2d import TransferFunction2D
from volren.model.volume import TetVolume, UniformVolume
from volren.renderers.base import KindSupport
from volren.samples import marschner_lobb, sample_transfer_functions

ALL_MODES = frozenset(BlendMode)


class Recorder:
    """A loaded ViewState and every Change it announces from now on."""

    def __init__(self, volume: UniformVolume | TetVolume | None = None) -> None:
        self.state = ViewState()
        if volume is not None:
            load(self.state, volume)
        self.changes: list[Change] = []
        self.state.subscribe(self.changes.append)

    def whats(self) -> list[str]:
        return [c.what for c in self.changes]


def load(state: ViewState, volume, settings: RenderSettings | None = None) -> None:
    state.load(volume, sample_transfer_functions()["marschner_lobb"], default_camera(volume), settings)


def changed_fields(before: RenderSettings, after: RenderSettings) -> dict[str, object]:
    old, new = before.to_dict(), after.to_dict()
    return {k: new[k] for k in new if new[k] != old[k]}


def kuhn_mesh(n_cubes: int = 2, notes: tuple[str, ...] = (), values=None) -> TetVolume:
    """Unit cubes in a row along x, each split into the 6 tetrahedra of Kuhn's triangulation."""
    points = np.array([(x, y, z) for z in (0, 1) for y in (0, 1) for x in range(n_cubes + 1)], float)
    index = {tuple(p): i for i, p in enumerate(points.astype(int))}
    tets = []
    for cube in range(n_cubes):
        for order in itertools.permutations(range(3)):
            corner = np.array([cube, 0, 0])
            path = [index[tuple(corner)]]
            for axis in order:
                corner = corner + np.eye(3, dtype=int)[axis]
                path.append(index[tuple(corner)])
            tets.append(path)
    fixed = repair_tets(points, np.array(tets)).tets
    vals = points[:, 0].copy() if values is None else values
    return TetVolume(points, fixed, vals, name="kuhn", notes=notes)


@pytest.fixture
def rec() -> Recorder:
    return Recorder(marschner_lobb(9))


@pytest.fixture
def make(qtbot):
    """Build a panel, registered with qtbot so it is closed after the test."""

    def build(cls, state: ViewState):
        panel = cls(state)
        qtbot.addWidget(panel)
        return panel

    return build


def press_spin_arrow(qtbot, spin: GestureSpinBox, up: bool = True) -> None:
    """Click a spin box arrow with the mouse: press (one step, auto-repeat would follow) and release."""
    option = QStyleOptionSpinBox()
    spin.initStyleOption(option)
    control = QStyle.SC_SpinBoxUp if up else QStyle.SC_SpinBoxDown
    where = spin.style().subControlRect(QStyle.CC_SpinBox, option, control, spin).center()
    qtbot.mousePress(spin, Qt.LeftButton, pos=where)
    qtbot.mouseRelease(spin, Qt.LeftButton, pos=where)


def type_into(qtbot, spin: GestureSpinBox, text: str) -> None:
    spin.lineEdit().selectAll()
    qtbot.keyClicks(spin.lineEdit(), text)
    qtbot.keyClick(spin, Qt.Key_Return)


# ---------------------------------------------------------------------------------- lighting
def test_each_lighting_control_edits_exactly_its_field(rec, make):
    panel = make(LightingPanel, rec.state)
    edits = [
        (lambda: panel.shade.setChecked(True), {"shade": True}),
        (lambda: panel.ambient.spin.setValue(0.35), {"ambient": 0.35}),
        (lambda: panel.diffuse.slider.setValue(25), {"diffuse": 0.25}),
        (lambda: panel.specular.spin.setValue(0.9), {"specular": 0.9}),
        (lambda: panel.specular_power.slider.setValue(63), {"specular_power": 64.0}),
    ]
    for edit, expected in edits:
        before = rec.state.settings
        edit()
        got = changed_fields(before, rec.state.settings)
        assert got.keys() == expected.keys()
        for name, value in expected.items():
            assert got[name] == pytest.approx(value)
    assert rec.whats() == ["settings"] * len(edits)
    assert not any(c.interactive for c in rec.changes)
    # slider and spin box of one control show the same value
    assert panel.diffuse.spin.value() == pytest.approx(0.25)
    assert panel.ambient.slider.value() == 35


def test_lighting_coefficients_follow_the_shade_checkbox(rec, make):
    panel = make(LightingPanel, rec.state)
    assert not panel.shade.isChecked()
    assert not any(c.isEnabled() for c in panel.coefficients)
    panel.shade.setChecked(True)
    assert rec.state.settings.shade
    assert all(c.isEnabled() for c in panel.coefficients)


def test_lighting_shows_state_changes_without_echo(rec, make):
    panel = make(LightingPanel, rec.state)
    rec.state.set_settings(rec.state.settings.with_(shade=True, ambient=0.42, specular_power=50.0))
    assert rec.whats() == ["settings"]
    assert panel.shade.isChecked()
    assert panel.ambient.spin.value() == pytest.approx(0.42)
    assert panel.ambient.slider.value() == 42
    assert panel.specular_power.spin.value() == pytest.approx(50.0)
    assert all(c.isEnabled() for c in panel.coefficients)


def test_lighting_shows_a_value_beyond_its_usual_range_unclamped(rec, make):
    panel = make(LightingPanel, rec.state)
    rec.state.set_settings(rec.state.settings.with_(specular_power=200.0))
    assert panel.specular_power.spin.value() == pytest.approx(200.0)
    assert rec.state.settings.specular_power == 200.0
    assert rec.whats() == ["settings"]


def test_a_slider_drag_is_one_interaction(rec, make):
    panel = make(LightingPanel, rec.state)
    slider = panel.ambient.slider
    slider.setSliderDown(True)  # what pressing the handle does: sliderPressed
    slider.setValue(30)
    slider.setValue(40)
    assert rec.state.interacting
    slider.setSliderDown(False)  # sliderReleased
    assert rec.changes == [Change("settings", True), Change("settings", True), Change("interaction", False)]
    assert rec.state.settings.ambient == pytest.approx(0.40)
    assert not rec.state.interacting


def test_pressing_a_slider_without_moving_it_asks_for_nothing(rec, make):
    panel = make(LightingPanel, rec.state)
    panel.diffuse.slider.setSliderDown(True)
    panel.diffuse.slider.setSliderDown(False)
    assert rec.changes == []


def test_spin_box_arrow_and_wheel_are_interactions_typing_is_not(rec, make, qtbot):
    panel = make(LightingPanel, rec.state)
    panel.shade.setChecked(True)
    panel.show()
    rec.changes.clear()
    spin = panel.specular_power.spin
    press_spin_arrow(qtbot, spin)
    assert rec.changes == [Change("settings", True), Change("interaction", False)]
    assert rec.state.settings.specular_power == pytest.approx(11.0)

    rec.changes.clear()
    wheel = QWheelEvent(
        QPointF(5, 5),
        QPointF(5, 5),
        QPoint(0, 0),
        QPoint(0, 120),
        Qt.NoButton,
        Qt.NoModifier,
        Qt.NoScrollPhase,
        False,
    )
    QApplication.sendEvent(spin, wheel)
    assert rec.changes == [Change("settings", True), Change("interaction", False)]
    assert rec.state.settings.specular_power == pytest.approx(12.0)

    rec.changes.clear()
    type_into(qtbot, spin, "33")
    assert rec.changes == [Change("settings", False)]
    assert rec.state.settings.specular_power == pytest.approx(33.0)


def test_lighting_without_shading_support_is_disabled_with_the_reason(rec, make):
    panel = make(LightingPanel, rec.state)
    rec.state.set_settings(rec.state.settings.with_(shade=True))
    panel.set_capabilities(KindSupport(shading=False))
    assert not panel.shade.isEnabled()
    assert not any(c.isEnabled() for c in panel.coefficients)
    assert "no shading" in panel.shade.toolTip() and "uniform" in panel.shade.toolTip()
    panel.set_capabilities(KindSupport(shading=True))
    assert panel.shade.isEnabled() and all(c.isEnabled() for c in panel.coefficients)
    panel.set_capabilities(None)
    assert panel.shade.isEnabled()
    assert rec.whats() == ["settings"]  # capabilities never edit the settings


# ---------------------------------------------------------------------------------- sampling
def test_each_sampling_control_edits_exactly_its_field(rec, make):
    panel = make(SamplingPanel, rec.state)
    assert panel.step.slider is None
    edits = [
        (lambda: panel.step.spin.setValue(1.25), {"step": 1.25}),
        (lambda: panel.preintegration.setChecked(True), {"preintegration": True}),
        (lambda: panel.jitter.setChecked(True), {"jitter": True}),
    ]
    for edit, expected in edits:
        before = rec.state.settings
        edit()
        assert changed_fields(before, rec.state.settings) == expected
    assert rec.whats() == ["settings"] * 3


def test_sampling_step_range_units_and_world_length(rec, make):
    panel = make(SamplingPanel, rec.state)
    spin = panel.step.spin
    assert (spin.minimum(), spin.maximum()) == (pytest.approx(0.05), pytest.approx(4.0))
    assert (
        "smallest voxel spacing" in panel.step.toolTip() and "mean tetrahedron edge" in panel.step.toolTip()
    )
    # marschner_lobb(9): spacing 2 / 8 = 0.25; the default step 0.5 is 0.125 world units
    assert "0.125 world units" in panel.step_length.text()
    spin.setValue(2.0)
    assert "0.5 world units" in panel.step_length.text()
    load(rec.state, kuhn_mesh(1))
    edge = (3 + 2 * math.sqrt(2) + math.sqrt(3)) / 6
    assert "tetrahedron edge" in panel.step_length.text()
    assert f"{2.0 * edge:.4g} world units" in panel.step_length.text()


def test_sampling_shows_state_changes_without_echo(rec, make):
    panel = make(SamplingPanel, rec.state)
    rec.state.set_settings(rec.state.settings.with_(step=0.01, preintegration=True, jitter=True))
    assert rec.whats() == ["settings"]
    assert panel.step.spin.value() == pytest.approx(0.01)  # below the usual range, shown as it is
    assert panel.preintegration.isChecked() and panel.jitter.isChecked()


def test_sampling_without_preintegration_support(rec, make):
    panel = make(SamplingPanel, rec.state)
    panel.set_capabilities(KindSupport(preintegration=False, shading=True))
    assert not panel.preintegration.isEnabled()
    assert "no pre-integration" in panel.preintegration.toolTip()
    assert panel.jitter.isEnabled() and panel.step.isEnabled()
    panel.set_capabilities(KindSupport(preintegration=True))
    assert panel.preintegration.isEnabled()
    assert "no pre-integration" not in panel.preintegration.toolTip()


# ------------------------------------------------------------------------------------- blend
def test_blend_combo_edits_only_the_blend_mode(rec, make, qtbot):
    panel = make(BlendPanel, rec.state)
    assert [BlendMode(panel.combo.itemData(i)) for i in range(panel.combo.count())] == list(BlendMode)
    before = rec.state.settings
    qtbot.keyClick(panel.combo, Qt.Key_Down)  # the person picks the next mode
    assert changed_fields(before, rec.state.settings) == {"blend_mode": "maximum"}
    qtbot.keyClick(panel.combo, Qt.Key_Down)
    assert rec.state.settings.blend_mode is BlendMode.MINIMUM
    assert rec.whats() == ["settings", "settings"]


def test_blend_shows_state_changes_without_echo(rec, make):
    panel = make(BlendPanel, rec.state)
    rec.state.set_settings(rec.state.settings.with_(blend_mode=BlendMode.AVERAGE))
    assert panel.combo.currentText() == "Average intensity"
    assert rec.whats() == ["settings"]


def test_blend_modes_the_renderer_lacks_are_disabled(rec, make, qtbot):
    panel = make(BlendPanel, rec.state)
    support = KindSupport(blend_modes=frozenset({BlendMode.COMPOSITE, BlendMode.MINIMUM}))
    panel.set_capabilities(support)
    enabled = {m for m in BlendMode if panel.mode_enabled(m)}
    assert enabled == {BlendMode.COMPOSITE, BlendMode.MINIMUM}
    assert "no maximum blend mode" in panel.mode_tooltip(BlendMode.MAXIMUM)
    qtbot.keyClick(panel.combo, Qt.Key_Down)  # skips the disabled maximum
    assert rec.state.settings.blend_mode is BlendMode.MINIMUM


def test_blend_modes_with_a_2d_tf_follow_blend_modes_2d(rec, make):
    panel = make(BlendPanel, rec.state)
    panel.set_capabilities(
        KindSupport(
            tf_dims=frozenset({1, 2}), blend_modes=ALL_MODES, blend_modes_2d=frozenset({BlendMode.COMPOSITE})
        )
    )
    assert all(panel.mode_enabled(m) for m in BlendMode)
    rec.state.set_transfer_function(TransferFunction2D((0, 1), (0, 1)))
    assert {m for m in BlendMode if panel.mode_enabled(m)} == {BlendMode.COMPOSITE}
    assert "2D transfer functions" in panel.mode_tooltip(BlendMode.AVERAGE)
    panel.set_capabilities(None)
    assert all(panel.mode_enabled(m) for m in BlendMode)


# -------------------------------------------------------------------------------------- crop
def test_crop_controls_give_the_box_in_world_units(rec, make):
    panel = make(CropPanel, rec.state)
    assert not panel.enable.isChecked() and not any(s.isEnabled() for s in panel.spins)
    assert [s.value() for s in panel.spins] == [-1, 1, -1, 1, -1, 1]
    panel.enable.setChecked(True)
    assert all(s.isEnabled() for s in panel.spins)
    assert rec.state.crop is None  # the whole volume: nothing cropped yet
    panel.spins[0].setValue(-0.5)
    panel.spins[5].setValue(0.25)
    assert rec.state.crop == (-0.5, 1.0, -1.0, 1.0, -1.0, 0.25)
    assert rec.whats() == ["crop", "crop"]
    # what is drawn is the grid cut to the box: x samples at -0.5 .. 1 (spacing 0.25), z at -1 .. 0.25
    assert rec.state.render_volume.dimensions == (7, 9, 6)


def test_crop_clamps_min_to_max(rec, make):
    panel = make(CropPanel, rec.state)
    panel.enable.setChecked(True)
    panel.spins[0].setValue(0.5)  # xmin
    panel.spins[1].setValue(-0.7)  # xmax below xmin: stops at xmin
    assert rec.state.crop[:2] == (0.5, 0.5)
    assert panel.spins[1].value() == pytest.approx(0.5)
    panel.spins[3].setValue(0.1)  # ymax
    panel.spins[2].setValue(0.9)  # ymin above ymax: stops at ymax
    assert rec.state.crop[2:4] == (0.1, 0.1)
    for change in rec.changes:
        assert change.what == "crop"
    crop = rec.state.crop
    assert all(crop[2 * a] <= crop[2 * a + 1] for a in range(3))


def test_crop_reset_and_switching_off_and_on(rec, make):
    panel = make(CropPanel, rec.state)
    panel.enable.setChecked(True)
    panel.spins[1].setValue(0.5)
    box = rec.state.crop
    assert box == (-1.0, 0.5, -1.0, 1.0, -1.0, 1.0)
    panel.enable.setChecked(False)
    assert rec.state.crop is None and panel.box() is None
    panel.enable.setChecked(True)  # the box comes back
    assert rec.state.crop == box
    panel.reset()
    assert rec.state.crop is None
    assert panel.box() == rec.state.volume.bounds
    assert [s.value() for s in panel.spins] == [-1, 1, -1, 1, -1, 1]
    assert rec.whats() == ["crop"] * 4


def test_crop_follows_the_state_without_echo(rec, make):
    panel = make(CropPanel, rec.state)
    rec.state.set_crop((-0.5, 0.5, -1.0, 0.0, -1.0, 1.0))
    assert rec.whats() == ["crop"]
    assert panel.enable.isChecked()
    assert [s.value() for s in panel.spins] == [-0.5, 0.5, -1, 0, -1, 1]
    rec.state.set_crop(None)  # undo, say: the controls show the whole volume, still switched on
    assert panel.enable.isChecked() and panel.box() == rec.state.volume.bounds
    # a new volume: controls laid out for its bounds, cropping off
    load(
        rec.state, UniformVolume(np.zeros((3, 4, 5), np.float32), spacing=(2.0, 1.0, 0.5), origin=(10, 0, 0))
    )
    assert not panel.enable.isChecked()
    assert [(s.minimum(), s.maximum()) for s in panel.spins[::2]] == [(10, 18), (0, 3), (0, 1)]
    assert [s.singleStep() for s in panel.spins[::2]] == [2.0, 1.0, 0.5]
    assert rec.whats() == ["crop", "crop", "volume"]


def test_crop_side_at_the_end_of_its_range_is_the_exact_bound(make):
    origin = (0.1234567, -3.3333333, 0.0)
    rec = Recorder(UniformVolume(np.zeros((4, 4, 4), np.float32), spacing=0.3, origin=origin))
    panel = make(CropPanel, rec.state)
    bounds = rec.state.volume.bounds
    assert panel.spins[0].decimals() == decimals_for(0.9) == 4  # the shown value is rounded ...
    panel.enable.setChecked(True)
    panel.spins[1].setValue(0.5)  # crop x from above
    panel.spins[0].setValue(0.4)
    panel.spins[0].setValue(panel.spins[0].minimum())  # back to the lower end
    assert rec.state.crop[0] == bounds[0]  # ... the box is exact
    assert rec.state.crop[2:] == bounds[2:]


def test_an_impossible_crop_box_is_reported_and_the_controls_restored(make):
    rec = Recorder(kuhn_mesh(2))  # x from 0 to 2, one cube of six tetrahedra per unit
    panel = make(CropPanel, rec.state)
    errors: list[tuple[str, str]] = []
    panel.errorOccurred.connect(lambda title, text: errors.append((title, text)))
    panel.enable.setChecked(True)
    panel.spins[1].setValue(1.0)  # the first cube only
    assert rec.state.crop == (0.0, 1.0, 0.0, 1.0, 0.0, 1.0)
    assert len(rec.state.render_volume.tets) == 6
    panel.spins[1].setValue(0.5)  # no tetrahedron lies wholly inside
    assert len(errors) == 1 and errors[0][0] == "Cropping"
    assert "no tetrahedron" in errors[0][1] and "\n" not in errors[0][1]
    assert rec.state.crop == (0.0, 1.0, 0.0, 1.0, 0.0, 1.0)
    assert panel.spins[1].value() == pytest.approx(1.0)
    assert panel.box() == rec.state.crop
    assert rec.whats() == ["crop"]


def test_holding_a_crop_arrow_is_one_interaction(rec, make, qtbot):
    panel = make(CropPanel, rec.state)
    panel.show()
    panel.enable.setChecked(True)
    press_spin_arrow(qtbot, panel.spins[0])  # xmin up by one sample
    assert rec.changes == [Change("crop", True), Change("interaction", False)]
    assert rec.state.crop[0] == pytest.approx(-0.75)


def test_crop_without_a_volume_is_disabled(make):
    rec = Recorder()
    panel = make(CropPanel, rec.state)
    assert not panel.enable.isEnabled()
    assert "Load a volume" in panel.toolTip()
    panel.reset()
    assert rec.changes == []


# -------------------------------------------------------------------------------- background
def test_background_picker(rec, make, qtbot):
    panel = make(BackgroundPanel, rec.state)
    assert panel.button.text() == "#1a1a1f"  # DEFAULT_BACKGROUND (0.1, 0.1, 0.12)
    offered: list[str] = []
    answers = [QColor(255, 128, 0), None, QColor(255, 128, 0)]

    def choose(initial: QColor) -> QColor | None:
        offered.append(initial.name())
        return answers.pop(0)

    panel.choose_color = choose
    qtbot.mouseClick(panel.button, Qt.LeftButton)
    assert rec.state.background == pytest.approx((1.0, 128 / 255, 0.0))
    assert panel.button.text() == "#ff8000"
    qtbot.mouseClick(panel.button, Qt.LeftButton)  # cancelled
    qtbot.mouseClick(panel.button, Qt.LeftButton)  # the same colour again
    assert offered == ["#1a1a1f", "#ff8000", "#ff8000"]
    assert rec.whats() == ["background"]


def test_background_follows_the_state(rec, make):
    panel = make(BackgroundPanel, rec.state)
    rec.state.set_background((0.0, 0.0, 1.0))
    assert panel.button.text() == "#0000ff"
    assert panel.button.icon().pixmap(16, 16).toImage().pixelColor(8, 8).name() == "#0000ff"
    assert rec.whats() == ["background"]


# ----------------------------------------------------------------------------- dataset facts
def test_dataset_facts_of_a_uniform_grid(rec, make):
    panel = make(DatasetInfoPanel, rec.state)
    facts = panel.facts()
    assert facts["Kind"] == "uniform grid"
    assert facts["Dimensions"] == "9 × 9 × 9"
    assert facts["Points"] == "729" and facts["Cells"] == "512"
    assert facts["Spacing"] == "0.25, 0.25, 0.25" and facts["Origin"] == "-1, -1, -1"
    assert facts["Bounds"] == "[-1, 1] × [-1, 1] × [-1, 1]"
    assert facts["Data type"] == "float32"
    values = rec.state.volume.values
    low, high = (float(x) for x in facts["Value range"].split(" to "))
    assert low == pytest.approx(float(values.min()), rel=1e-5) and high == pytest.approx(float(values.max()))
    assert facts["Non-finite values"] == "0"
    assert panel.notes() == [] and panel.notes_label.text() == "Notes: none"
    assert not panel.empty.isVisibleTo(panel)
    rec.state.set_crop((-1.0, 0.0, -1.0, 1.0, -1.0, 1.0))  # x samples at -1 .. 0: five of them
    assert panel.facts()["Cropped to"] == "5 × 9 × 9"


def test_a_crop_drag_sets_the_facts_in_place_and_cuts_no_grid(rec, make, monkeypatch):
    """At every step of a crop face's drag the panel cut the grid (a copy of its samples and their
    range) and rebuilt its form on the GUI thread: 13 ms a step on bonsai. Where the renderer clips,
    nothing is cut now, and the rows' widgets stay."""
    import volren.model.volume as volume_module

    assert rec.state.clips()  # the state's renderer clips: a cut grid is not what it draws
    panel = make(DatasetInfoPanel, rec.state)
    rec.state.set_crop((-1.0, 0.5, -1.0, 1.0, -1.0, 1.0))
    widgets = list(panel._values.values())
    grids: list[object] = []
    built = volume_module.UniformVolume.__post_init__
    monkeypatch.setattr(volume_module.UniformVolume, "__post_init__", lambda self: grids.append(built(self)))
    rec.state.begin_interaction()
    for x in (0.25, 0.0, -0.25, -0.5):  # the face at x samples -1 .. x of 0.25 apart
        rec.state.set_crop((-1.0, x, -1.0, 1.0, -1.0, 1.0))
        assert panel.facts()["Cropped to"] == f"{round((x + 1.0) / 0.25) + 1} × 9 × 9"
    rec.state.end_interaction()
    assert grids == []
    assert list(panel._values.values()) == widgets


def test_dataset_facts_count_non_finite_values(make):
    values = np.ones((3, 3, 3), np.float32)
    values[0, 0, :2] = np.nan
    values[2, 2, 2] = np.inf
    rec = Recorder(UniformVolume(values, name="holes"))
    panel = make(DatasetInfoPanel, rec.state)
    assert panel.facts()["Non-finite values"] == "3"
    assert panel.facts()["Value range"] == "1 to 1"
    assert len(panel.notes()) == 1 and "3 non-finite values" in panel.notes()[0]


def test_dataset_facts_of_a_mesh_with_notes(make):
    notes = (
        "kuhn: dropped 3 cells that are not 3D (3 triangles), reoriented 2 inverted tetrahedra",
        "kuhn: array 'p' is cell data; averaged it onto the points",
    )
    values = np.arange(12, dtype=np.float64)
    rec = Recorder(kuhn_mesh(2, notes=notes, values=values))
    panel = make(DatasetInfoPanel, rec.state)
    facts = panel.facts()
    assert facts["Kind"] == "tetrahedral mesh"
    assert facts["Points"] == "12" and facts["Cells"] == "12 tetrahedra"
    # Kuhn tetrahedra of unit cubes: three edges of 1, two face diagonals, one space diagonal
    assert float(facts["Mean edge length"]) == pytest.approx(
        (3 + 2 * math.sqrt(2) + math.sqrt(3)) / 6, rel=1e-5
    )
    assert facts["Bounds"] == "[0, 2] × [0, 1] × [0, 1]"
    assert facts["Value range"] == "0 to 11" and facts["Data type"] == "float64"
    assert "Dimensions" not in facts and "Spacing" not in facts
    assert panel.notes() == list(notes)
    assert panel.notes_label.text() == "Notes (2)"


def test_dataset_panel_without_a_volume(make):
    rec = Recorder()
    panel = make(DatasetInfoPanel, rec.state)
    assert panel.empty.text() == "No volume" and panel.empty.isVisibleTo(panel)
    assert panel.facts() == {} and panel.notes() == []
    load(rec.state, marschner_lobb(5))
    assert panel.facts()["Dimensions"] == "5 × 5 × 5" and not panel.empty.isVisibleTo(panel)


# ------------------------------------------------------------------------------- all panels
PANELS = (LightingPanel, SamplingPanel, BlendPanel, CropPanel, BackgroundPanel, DatasetInfoPanel)


@pytest.mark.parametrize(
    "change",
    [
        lambda s: load(s, marschner_lobb(5), RenderSettings(step=2.0, shade=True, blend_mode="maximum")),
        # values finer than the spin boxes' decimals: showing them rounded must not write them back
        lambda s: s.set_settings(
            RenderSettings(ambient=0.123456, step=0.33333, preintegration=True, jitter=True)
        ),
        lambda s: s.set_crop((-1.0, 0.0, -1.0, 1.0, -1.0, 1.0)),
        lambda s: s.set_background((0.5, 0.5, 0.5)),
    ],
    ids=["load", "settings", "crop", "background"],
)
def test_no_panel_echoes_a_state_change(rec, make, change):
    panels = [make(cls, rec.state) for cls in PANELS]
    change(rec.state)
    assert len(rec.changes) == 1
    assert panels[0].shade.isChecked() == rec.state.settings.shade
    assert panels[1].step.spin.value() == pytest.approx(rec.state.settings.step, abs=1e-3)
    assert panels[2].combo.currentData() == rec.state.settings.blend_mode.value


def test_a_deleted_panel_stops_following_the_state(rec, qtbot):
    panels = [cls(rec.state) for cls in PANELS]  # not handed to qtbot: deleted here
    for panel in panels:
        sip.delete(panel)
    rec.state.set_settings(rec.state.settings.with_(ambient=0.3))  # would raise on a dead widget
    rec.state.set_crop((-1.0, 0.0, -1.0, 1.0, -1.0, 1.0))
    assert rec.whats() == ["settings", "crop"]


def test_a_detached_panel_no_longer_follows(rec, make):
    panel = make(LightingPanel, rec.state)
    panel.detach()
    rec.state.set_settings(rec.state.settings.with_(shade=True))
    assert not panel.shade.isChecked()
