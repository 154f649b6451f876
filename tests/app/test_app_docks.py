"""The docks in the window: editors and panels drive the frames, undo from the Edit menu,
Ctrl+click on the volume places a 2D widget, panels follow the renderer's capabilities."""

from __future__ import annotations

import numpy as np
import pytest
from PyQt5.QtCore import QPoint, Qt

from tests.app.conftest import FRAME_TIMEOUT_MS

pytestmark = pytest.mark.qt


def frame_after(qtbot, window, act) -> object:
    """Run `act` and return the full-quality frame that follows it."""
    with qtbot.waitSignal(window.fullFrameShown, timeout=FRAME_TIMEOUT_MS) as blocker:
        act()
    return blocker.args[0]


def test_the_window_has_the_editors_and_panels_docked(loaded_window):
    w = loaded_window
    docks = w.docks
    assert (
        docks.tf_dock.widget().widget() is docks.tf_panel and not docks.tf_dock.isHidden()
    )  # in a scroll area
    assert docks.tf_panel.tabs.currentWidget() is docks.tf_panel.editor_1d
    assert docks.dataset.facts()["Dimensions"] == " × ".join(str(n) for n in w.state.volume.dimensions)
    width, height = w.viewport.pixel_size()
    assert width >= 400 and height >= 400, "the docks squeeze the viewport"


@pytest.mark.parametrize("size", [(1300, 760), (900, 600), (640, 480)])
def test_the_viewport_keeps_half_the_window_as_it_shrinks(loaded_window, qtbot, size):
    """Issue 23: the docks kept their width (at 900x600 the viewport was 169 px wide); they give
    way down to a minimum, their controls scrolling, and stay visible."""
    w = loaded_window
    w.resize(*size)
    qtbot.waitUntil(lambda: w.width() == size[0], timeout=2000)
    qtbot.wait(50)
    assert w.viewport.width() >= 0.47 * w.width(), (w.viewport.width(), w.width())
    for dock in (w.docks.tf_dock, w.docks.settings_dock):
        assert dock.isVisible() and dock.width() >= 150


def test_a_click_in_the_1d_editor_renders_a_new_frame_and_undo_restores_it(loaded_window, qtbot):
    w = loaded_window
    curve = w.docks.tf_panel.editor_1d.curve
    before = w.viewport.frame.rgb.copy()
    points = w.state.transfer_function.opacity_points.copy()
    lo, hi = w.state.volume.value_range
    at = curve.position_of(lo + 0.6 * (hi - lo), 1.0)  # an opaque point in the middle of the data
    frame = frame_after(qtbot, w, lambda: qtbot.mouseClick(curve, Qt.LeftButton, pos=QPoint(at)))
    assert len(w.state.transfer_function.opacity_points) == len(points) + 1
    assert np.abs(frame.rgb.astype(int) - before).max() > 20, "the edit did not change the frame"
    assert w.docks.undo_action.isEnabled()
    frame = frame_after(qtbot, w, w.docks.undo_action.trigger)
    np.testing.assert_array_equal(w.state.transfer_function.opacity_points, points)
    assert np.abs(frame.rgb.astype(int) - before).max() <= 1


def test_a_lighting_edit_reaches_the_renderer(loaded_window, qtbot):
    w = loaded_window
    assert not w.state.settings.shade
    frame = frame_after(qtbot, w, lambda: w.docks.lighting.shade.click())
    assert w.state.settings.shade and frame.full


def test_ctrl_click_on_the_volume_places_a_2d_widget(loaded_window, qtbot):
    w = loaded_window
    editor = w.docks.tf_panel.editor_2d
    frame_after(qtbot, w, editor.use_2d_button.click)
    assert w.state.transfer_function.dims == 2 and w.docks.tf_panel.tabs.currentWidget() is editor
    from volren.app.core.picking import pick

    tf = w.state.transfer_function
    widgets = len(tf.widgets)
    width, height = w.viewport.pixel_size()
    hit = pick(w.state.volume, tf, w.state.camera, width // 2, height // 2, width, height)
    assert hit is not None
    w.docks.pick(width // 2, height // 2)  # what the viewport's Ctrl+click emits
    assert len(tf.widgets) == widgets + 1
    assert tf.widgets[-1].center == pytest.approx((hit.value, hit.gradient_magnitude))


def test_ctrl_click_with_a_1d_tf_only_explains(loaded_window):
    w = loaded_window
    width, height = w.viewport.pixel_size()
    before = w.state.transfer_function.to_dict()
    w.docks.pick(width // 2, height // 2)
    assert w.state.transfer_function.to_dict() == before and "2D" in w.statusBar().currentMessage()


def test_panels_follow_the_renderer_capabilities(loaded_window, qtbot):
    w = loaded_window
    assert w.docks.current_support() == w.registry.capabilities("vtk").kinds["uniform"]
    vtk_pre = w.registry.capabilities("vtk").kinds["uniform"].preintegration
    assert w.docks.sampling.preintegration.isEnabled() == vtk_pre
    frame_after(qtbot, w, lambda: w.renderers.switch("slicer"))
    assert w.docks.sampling.preintegration.isEnabled()  # the slicer pre-integrates


def test_a_crop_error_is_reported_in_one_line(loaded_window, error_boxes):
    w = loaded_window
    w.docks.crop.errorOccurred.emit("Cannot crop", "crop box: xmin 2 is above xmax 1")
    assert error_boxes == [("Cannot crop", "crop box: xmin 2 is above xmax 1")]


def test_the_docks_show_their_whole_width_at_the_default_window_size(make_window, ini, fake_renderers, qtbot):
    """At the app's default size no dock scrolls sideways: the TF editor (either tab), the
    rendering settings (taller than the dock: its vertical scroll bar takes room too) and the
    dataset facts of a volume with a long file name, long array names and a long note."""
    from volren.app.core.loading import LoadedInput
    from volren.app.main import DEFAULT_WINDOW_SIZE
    from volren.model.transfer_function import TransferFunction1D
    from volren.model.volume import UniformVolume

    name = "ct_abdomen_patient_000042_series_0003_reconstructed_0.625mm.nrrd"
    arrays = (
        "density_after_the_second_correction_pass",
        "density_after_the_second_correction_pass:magnitude",
    )
    values = np.arange(6 * 7 * 8, dtype=np.float32).reshape(8, 7, 6)
    volume = UniformVolume(values, spacing=(0.625, 0.625, 0.625), origin=(-123.4567, -98.7654, 1234.5678), name=name,
                           notes=(f"{name}: 12,345 cells of a kind volren does not draw were dropped",),
                           scalars=arrays[0], arrays=arrays)  # fmt: skip
    w = make_window(settings=ini)
    w.resize(*DEFAULT_WINDOW_SIZE)
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.files.apply_loaded(LoadedInput(volume, TransferFunction1D.ramp(0.0, 335.0), source=name), "fake")
    docks = w.docks
    for dock, show in ((docks.tf_dock, lambda: docks.tf_panel.tabs.setCurrentIndex(0)),
                       (docks.tf_dock, lambda: docks.tf_panel.tabs.setCurrentIndex(1)),
                       (docks.settings_dock, docks.settings_dock.raise_),
                       (docks.dataset_dock, docks.dataset_dock.raise_)):  # fmt: skip
        show()
        qtbot.wait(50)
        scroll = dock.widget()
        needed, shown = scroll.widget().minimumSizeHint().width(), scroll.viewport().width()
        assert needed <= shown and not scroll.horizontalScrollBar().isVisible(), (
            dock.windowTitle(),
            needed,
            shown,
        )
    assert docks.dataset.facts()["Name"] == name  # shown whole where it fits, in full in its tooltip
