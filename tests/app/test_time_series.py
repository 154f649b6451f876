"""Time series (issue 23): a .pvd or a folder of volumes opens with a time slider; steps are read
off the GUI thread, neighbours ahead, and each keeps the TF, camera and settings."""

from __future__ import annotations

import json
import threading
from pathlib import Path

import numpy as np
import pytest

from tests.app.test_app_files import TIMEOUT_MS
from volren.app.files.series_steps import CACHED_STEPS, SeriesSteps
from volren.errors import VolrenError
from volren.io.series_io import is_series, load_series
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import UniformVolume


def write_steps(folder: Path, count: int, names=None) -> list[Path]:
    """`count` small .vti files whose values are the step number plus a ramp."""
    import pyvista as pv

    paths = []
    for index in range(count):
        grid = pv.ImageData(dimensions=(5, 4, 3))
        grid.point_data["density"] = np.arange(grid.n_points, dtype=np.float32) / grid.n_points + index
        path = folder / (names[index] if names else f"step_{index}.vti")
        grid.save(path)
        paths.append(path)
    return paths


def write_pvd(path: Path, entries: list[tuple[float, str]], extra: str = "") -> Path:
    rows = "".join(f'<DataSet timestep="{t}" part="0" file="{name}"/>' for t, name in entries)
    path.write_text(f'<?xml version="1.0"?><VTKFile type="Collection" version="0.1"><Collection>{rows}{extra}'
                    "</Collection></VTKFile>")  # fmt: skip
    return path


# ------------------------------------------------------------------------------- the list of steps
def test_a_pvd_lists_its_steps_by_time_relative_to_itself(tmp_path):
    (tmp_path / "data").mkdir()
    write_steps(tmp_path / "data", 3)
    pvd = write_pvd(
        tmp_path / "run.pvd", [(0.5, "data/step_1.vti"), (0.0, "data/step_0.vti"), (2.5, "data/step_2.vti")]
    )
    series = load_series(pvd)
    assert is_series(pvd) and len(series) == 3
    assert [p.name for p in series.steps] == ["step_0.vti", "step_1.vti", "step_2.vti"]
    assert series.times == (0.0, 0.5, 2.5)
    assert series.label(1) == "step 2 of 3 (t = 0.5, step_1.vti)"


def test_a_folder_of_volumes_is_a_series_in_natural_order_and_other_folders_are_not(tmp_path):
    write_steps(tmp_path, 3, ["t2.vti", "t10.vti", "t1.vti"])
    (tmp_path / "notes.txt").write_text("not a volume")
    series = load_series(tmp_path)
    assert [p.name for p in series.steps] == ["t1.vti", "t2.vti", "t10.vti"] and series.times == (
        0.0,
        1.0,
        2.0,
    )
    single = tmp_path / "single"
    single.mkdir()
    write_steps(single, 1)
    dicom = tmp_path / "dicom"
    dicom.mkdir()
    for k in range(3):
        (dicom / f"slice{k}.dcm").write_bytes(b"")
    assert is_series(tmp_path) and not is_series(single) and not is_series(dicom)
    with pytest.raises(VolrenError, match="needs two or more volume files"):
        load_series(single)


@pytest.mark.parametrize(
    "text, message",
    [
        ("<VTKFile", "not a readable .pvd collection"),
        ('<VTKFile type="UnstructuredGrid"/>', "not a ParaView data collection"),
        ('<VTKFile type="Collection"><Collection/></VTKFile>', "lists no data sets"),
        (
            '<VTKFile type="Collection"><Collection><DataSet timestep="x" file="a.vti"/></Collection></VTKFile>',
            "timestep 'x' is not a number",
        ),
        (
            '<VTKFile type="Collection"><Collection><DataSet timestep="0" file="gone.vti"/></Collection></VTKFile>',
            "1 of its 1 files are missing, e.g. gone.vti",
        ),
        (
            '<VTKFile type="Collection"><Collection><DataSet timestep="0" part="1" file="a.vti"/></Collection></VTKFile>',
            "several parts per time step",
        ),
        (
            '<VTKFile type="Collection"><Collection><DataSet timestep="0"/></Collection></VTKFile>',
            "has no 'file'",
        ),
    ],
)
def test_bad_pvd_files_are_one_line_errors_naming_the_file(tmp_path, text, message):
    path = tmp_path / "bad.pvd"
    path.write_text(text)
    with pytest.raises(VolrenError, match=message) as exc:
        load_series(path)
    assert str(exc.value).startswith(str(path)) and "\n" not in str(exc.value)


# ----------------------------------------------------------------------------- reading ahead
class CountingReader:
    def __init__(self, fail: int | None = None) -> None:
        self.read: list[int] = []
        self.fail = fail
        self.threads: set[threading.Thread] = set()

    def __call__(self, path: Path, scalars: str | None) -> UniformVolume:
        index = int(path.stem.split("_")[1])
        self.read.append(index)
        self.threads.add(threading.current_thread())
        if index == self.fail:
            raise VolrenError(f"{path}: truncated")
        return UniformVolume(np.full((2, 2, 2), float(index)), name=path.name)


def test_steps_are_read_off_the_gui_thread_neighbours_ahead_and_a_few_kept(qtbot, tmp_path):
    write_steps(tmp_path, 6)
    series = load_series(tmp_path)
    reader = CountingReader()
    steps = SeriesSteps(series, read=reader)
    with qtbot.waitSignal(steps.stepReady, timeout=TIMEOUT_MS) as ready:
        steps.request(2)
    assert ready.args[0] == 2 and float(ready.args[1].values[0, 0, 0]) == 2.0
    qtbot.waitUntil(lambda: steps.reading is None and set(steps.cached) == {1, 2, 3}, timeout=TIMEOUT_MS)
    assert reader.read[0] == 2 and sorted(reader.read[1:]) == [1, 3]  # the neighbours, read ahead
    assert threading.main_thread() not in reader.threads
    answers = []
    steps.stepReady.connect(lambda index, volume: answers.append(index))
    steps.request(3)  # in memory: answered at once, without a read
    assert answers == [3] and reader.read.count(3) == 1
    qtbot.waitUntil(lambda: steps.reading is None and 4 in steps.cached, timeout=TIMEOUT_MS)
    assert len(steps.cached) <= CACHED_STEPS and 3 in steps.cached
    assert steps.shutdown()


def test_a_step_that_cannot_be_read_is_reported(qtbot, tmp_path):
    write_steps(tmp_path, 3)
    steps = SeriesSteps(load_series(tmp_path), read=CountingReader(fail=1))
    with qtbot.waitSignal(steps.stepFailed, timeout=TIMEOUT_MS) as failed:
        steps.request(1)
    assert failed.args == [1, f"{tmp_path / 'step_1.vti'}: truncated"]
    with pytest.raises(IndexError):
        steps.request(3)
    assert steps.shutdown()


# ------------------------------------------------------------------------------------- the window
def test_opening_a_pvd_shows_the_time_bar_and_steps_keep_the_view_and_undo(make_window, ini, fake_renderers,
                                                                            qtbot, tmp_path):  # fmt: skip
    paths = write_steps(tmp_path, 4)
    pvd = write_pvd(tmp_path / "run.pvd", [(0.1 * k, p.name) for k, p in enumerate(paths)])
    w = make_window(settings=ini)
    with qtbot.waitSignal(w.fullFrameShown, timeout=TIMEOUT_MS):
        w.files.open_input(pvd, renderer="fake")
    time = w.time
    assert (
        time.isVisible() and time.slider.maximum() == 3 and time.label.text().startswith("step 1 of 4 (t = 0")
    )
    edited = TransferFunction1D.ramp(0.5, 3.5, 0.4)
    w.state.set_transfer_function(edited)
    w.state.set_camera(w.state.camera.azimuth(25))
    camera = w.state.camera
    assert w.docks.undo_action.isEnabled()
    time.slider.setValue(2)
    qtbot.waitUntil(lambda: time.shown_step == 2, timeout=TIMEOUT_MS)
    assert time.label.text() == "step 3 of 4 (t = 0.2, step_2.vti)"
    assert float(w.state.volume.values.min()) == pytest.approx(2.0)
    assert w.state.transfer_function is edited and w.state.camera == camera
    assert w.docks.undo_action.isEnabled()  # stepping keeps the TF's history
    assert w.scenes.volume_path == str(paths[2])  # a scene saved now names the step shown
    time.play_button.setChecked(True)
    qtbot.waitUntil(lambda: time.shown_step == 0, timeout=TIMEOUT_MS)  # 3, then round to 0
    time.play_button.setChecked(False)
    with qtbot.waitSignal(w.files.loadFinished, timeout=TIMEOUT_MS):
        w.files.open_input(paths[1], renderer="fake")  # a single file: no time bar
    assert not time.isVisible() and time.series is None


def test_a_series_with_a_broken_step_reports_it_and_keeps_what_is_shown(make_window, ini, fake_renderers, qtbot,
                                                                        tmp_path, error_boxes):  # fmt: skip
    paths = write_steps(tmp_path, 3)
    paths[2].write_bytes(b"<VTKFile truncated")
    w = make_window(settings=ini)
    with qtbot.waitSignal(w.fullFrameShown, timeout=TIMEOUT_MS):
        w.files.open_input(tmp_path, renderer="fake")
    shown = w.state.volume
    qtbot.waitUntil(lambda: len(error_boxes) == 0 and w.time.steps.reading is None, timeout=TIMEOUT_MS)
    w.time.slider.setValue(2)
    qtbot.waitUntil(lambda: len(error_boxes) == 1, timeout=TIMEOUT_MS)
    title, text = error_boxes[0]
    assert title == "Cannot show the time step" and "step_2.vti" in text and "\n" not in text
    assert w.state.volume is shown and w.time.shown_step == 0


# ------------------------------------------------------------------------------- OME-Zarr levels
def test_an_ome_zarr_image_opens_coarse_at_once_and_refines_to_full_resolution(make_window, ini, fake_renderers,
                                                                               qtbot, tmp_path):  # fmt: skip
    """Issue 24: the app opens at the coarsest level at once and refines (here in the background,
    level after level, the view kept)."""
    pytest.importorskip("zarr", reason="volren[zarr] is part of the test set-up")
    from volren.io.ome_zarr_io import save_ome_zarr

    rng = np.random.default_rng(3)
    full = UniformVolume(
        rng.integers(0, 1000, (20, 24, 28)).astype(np.uint16), spacing=(1.0, 1.0, 2.0), name="c"
    )
    path = tmp_path / "cells.zarr"
    save_ome_zarr(full, path, chunk=8, levels=3)
    w = make_window(settings=ini)
    shown = []
    w.state.subscribe(
        lambda change: shown.append(w.state.volume.dimensions) if change.what == "volume" else None
    )
    with qtbot.waitSignal(w.files.loadFinished, timeout=TIMEOUT_MS):
        w.files.open_input(path, renderer="fake")
    tf, camera = w.state.transfer_function, w.state.camera
    qtbot.waitUntil(lambda: w.state.volume.dimensions == (28, 24, 20), timeout=TIMEOUT_MS)
    assert shown == [(7, 6, 5), (14, 12, 10), (28, 24, 20)]  # coarsest first, then each finer level
    np.testing.assert_array_equal(w.state.volume.values, full.values)
    assert w.state.transfer_function is tf and w.state.camera == camera
    assert w.state.source == "cells.zarr (level 0)" and not w.files.refiner.pending


def test_the_app_refines_only_up_to_the_memory_allowed(
    make_window, ini, fake_renderers, qtbot, tmp_path, error_boxes
):
    """`volren view x.zarr --memory SIZE`: the refinement stops at the finest level within SIZE,
    and an image whose coarsest level is larger says so in one line."""
    pytest.importorskip("zarr", reason="volren[zarr] is part of the test set-up")
    from volren.bricked.zarr_input import renderer_copy_bytes
    from volren.io.ome_zarr_io import save_ome_zarr

    full = UniformVolume(np.arange(20 * 24 * 28, dtype=np.uint16).reshape(20, 24, 28), name="c")
    path = tmp_path / "cells.zarr"
    save_ome_zarr(full, path, chunk=8, levels=3)
    w = make_window(settings=ini)
    # level 1 drawn fits: its uint16 values and the copies of a renderer not measured (the most), as
    # `volren render` counts them; level 0 does not, though its values alone would
    drawn_per_voxel = 2 + renderer_copy_bytes("fake")
    w.files.zarr_memory = 14 * 12 * 10 * drawn_per_voxel
    assert 28 * 24 * 20 * 2 <= w.files.zarr_memory < 28 * 24 * 20 * drawn_per_voxel
    shown = []
    w.state.subscribe(
        lambda change: shown.append(w.state.volume.dimensions) if change.what == "volume" else None
    )
    with qtbot.waitSignal(w.files.loadFinished, timeout=TIMEOUT_MS):
        w.files.open_input(path, renderer="fake")
    qtbot.waitUntil(lambda: w.state.volume.dimensions == (14, 12, 10), timeout=TIMEOUT_MS)
    qtbot.wait(200)
    assert shown == [(7, 6, 5), (14, 12, 10)] and not w.files.refiner.pending
    w.files.zarr_memory = 100
    w.files.open_input(path, renderer="fake")
    qtbot.waitUntil(lambda: len(error_boxes) == 1, timeout=TIMEOUT_MS)
    title, text = error_boxes[0]
    assert (
        title == "Cannot open"
        and (
            "even the coarsest level takes 6.6 KiB drawn by renderer fake (its values and "
            "the renderer's copies), more than the memory allowed (100 bytes)"
        )
        in text
    )
    assert w.state.volume.dimensions == (14, 12, 10)  # what was shown stays


def test_a_scripted_screenshot_of_an_ome_zarr_image_waits_for_its_finest_level(make_window, ini, fake_renderers,
                                                                                tmp_path):  # fmt: skip
    """`volren view x.zarr --screenshot` must not capture the coarse level shown first."""
    pytest.importorskip("zarr", reason="volren[zarr] is part of the test set-up")
    from volren.app.main import _screenshot
    from volren.io.ome_zarr_io import save_ome_zarr

    full = UniformVolume(np.arange(20 * 24 * 28, dtype=np.float32).reshape(20, 24, 28), name="c")
    path = tmp_path / "cells.zarr"
    save_ome_zarr(full, path, chunk=8, levels=3)
    w = make_window(settings=ini)
    shot = tmp_path / "shot.png"
    assert _screenshot(w, path, None, None, "fake", shot, timeout_s=60, traceback=False) == 0
    assert shot.is_file() and w.state.volume.dimensions == (28, 24, 20)


# ------------------------------------------------------------------------------------- scenes
@pytest.mark.parametrize("opened", ["run.pvd", "steps"])
def test_a_scene_saved_on_a_step_reopens_the_series_at_that_step(make_window, ini, fake_renderers, qtbot, tmp_path,
                                                                 error_boxes, opened):  # fmt: skip
    """Save Scene on step 3 of 4 of a .pvd or a folder: the scene names the series and the step
    (the volume path still that step's file), and opening it shows the whole series at that step."""
    (tmp_path / "steps").mkdir()
    paths = write_steps(tmp_path / "steps", 4)
    write_pvd(tmp_path / "run.pvd", [(0.1 * k, f"steps/{p.name}") for k, p in enumerate(paths)])
    w = make_window(settings=ini)
    with qtbot.waitSignal(w.fullFrameShown, timeout=TIMEOUT_MS):
        w.files.open_input(tmp_path / opened, renderer="fake")
    w.time.show_step(2)
    qtbot.waitUntil(lambda: w.time.shown_step == 2, timeout=TIMEOUT_MS)
    scene = tmp_path / "scenes" / "run-step.json"
    scene.parent.mkdir()
    assert w.scenes.save(scene)
    saved = json.loads(scene.read_text())
    assert saved["time_series"] == {"path": f"../{opened}", "step": 2}
    assert saved["volume"]["path"] == "../steps/step_2.vti"  # what readers without series support read

    other = make_window(settings=ini)
    with qtbot.waitSignal(other.fullFrameShown, timeout=TIMEOUT_MS):
        other.files.open_input(scene)
    time = other.time
    assert time.isVisible() and time.series.source == tmp_path / opened and time.series.steps == tuple(paths)
    assert time.shown_step == 2 and time.slider.value() == 2 and time.slider.maximum() == 3
    assert time.label.text().startswith("step 3 of 4") and float(other.state.volume.values.min()) == 2.0
    assert other.scenes.volume_path == str(paths[2])
    time.show_step(3)
    qtbot.waitUntil(lambda: time.shown_step == 3, timeout=TIMEOUT_MS)
    assert float(other.state.volume.values.min()) == 3.0 and error_boxes == []
