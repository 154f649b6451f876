"""The view state's crop box and the undo history recorded from the state."""

from __future__ import annotations

import pytest

from volren.app.core.state import Change, ViewState, default_camera
from volren.app.tf_editor.history import TFHistory
from volren.errors import VolrenError
from volren.model import TFWidget, TransferFunction2D
from volren.samples import marschner_lobb, sample_transfer_functions


@pytest.fixture
def state() -> tuple[ViewState, list[Change]]:
    s = ViewState()
    volume = marschner_lobb(9)  # bounds -1..1, spacing 0.25
    s.load(volume, sample_transfer_functions()["marschner_lobb"], default_camera(volume), source="ml")
    changes: list[Change] = []
    s.subscribe(changes.append)
    return s, changes


def test_crop_gives_the_renderers_the_part_inside(state):
    s, changes = state
    assert s.render_volume is s.volume
    s.set_crop((-1.0, 0.0, -1.0, 1.0, -1.0, 1.0))
    assert changes == [Change("crop", False)]
    cropped = s.render_volume
    assert cropped.dimensions == (5, 9, 9) and cropped.bounds[:2] == (-1.0, 0.0)
    assert s.render_volume is cropped  # made once per box
    s.set_crop((-1.0, 0.0, -1.0, 1.0, -1.0, 1.0))
    assert len(changes) == 1  # the same box again: nothing to announce


def test_a_box_covering_everything_is_no_crop_and_a_new_volume_clears_it(state):
    s, changes = state
    s.set_crop((-5, 5, -5, 5, -5, 5))
    assert s.crop is None and changes == []
    s.set_crop((-1.0, 0.0, -1.0, 1.0, -1.0, 1.0))
    s.load(s.volume, s.transfer_function, s.camera)
    assert s.crop is None and s.render_volume is s.volume


def test_a_malformed_box_is_refused_before_it_reaches_a_renderer(state):
    s, changes = state
    with pytest.raises(VolrenError):
        s.set_crop((1.0, 0.0, -1.0, 1.0, -1.0, 1.0))
    assert s.crop is None and changes == []


def test_history_records_finished_edits_once_and_undoes_them(qapp, state):
    s, _ = state
    history = TFHistory(s)
    tf = s.transfer_function
    original = tf.opacity_points.copy()
    original_unit = tf.opacity_unit_distance
    assert original_unit != 0.5
    s.begin_interaction()  # a drag: three previews, one undo step
    for peak in (0.2, 0.4, 0.6):
        tf.set_opacity_points([[-1.0, 0.0], [1.0, peak]])
    assert history.stack.count() == 0
    s.end_interaction()
    assert history.stack.count() == 1
    tf.set_opacity_unit_distance(0.5)  # a typed value: its own step
    assert history.stack.count() == 2
    s.set_camera(s.camera.zoom(2.0))  # not a TF edit
    assert history.stack.count() == 2
    history.undo()
    assert s.transfer_function.opacity_unit_distance == original_unit
    assert s.transfer_function.opacity_points[-1, 1] == 0.6
    history.undo()
    assert s.transfer_function.opacity_points.tolist() == original.tolist()
    history.redo()
    history.redo()
    assert (
        s.transfer_function.opacity_points[-1, 1] == 0.6 and s.transfer_function.opacity_unit_distance == 0.5
    )
    assert history.stack.count() == 2  # undo/redo themselves record nothing


def test_history_spans_1d_and_2d_and_restarts_with_a_new_volume(qapp, state):
    s, _ = state
    history = TFHistory(s)
    one_d = s.transfer_function.to_dict()
    s.set_transfer_function(
        TransferFunction2D(
            (-1.0, 1.0), (0.0, 4.0), [TFWidget.box((0.0, 1.0), (0.0, 4.0), (1.0, 0.5, 0.0), 0.5)]
        )
    )
    assert history.stack.count() == 1 and history.stack.undoText() == "new transfer function"
    history.undo()
    assert s.transfer_function.dims == 1 and s.transfer_function.to_dict() == one_d
    history.redo()
    assert s.transfer_function.dims == 2
    s.load(s.volume, s.transfer_function, s.camera)
    assert history.stack.count() == 0
