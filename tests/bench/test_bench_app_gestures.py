"""`volren bench app`'s gesture table (`volren.app.timing.gestures`), on a bundled sample."""

from __future__ import annotations

import math
import os
import tempfile
import time

import pytest

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
os.environ.setdefault("XDG_RUNTIME_DIR", tempfile.mkdtemp(prefix="volren-xdg-"))
os.environ.setdefault("XDG_CONFIG_HOME", tempfile.mkdtemp(prefix="volren-config-"))


def test_the_stall_probe_sees_the_gui_thread_held(qapp):
    """The probe's number is the GUI thread's longest gap: a 200 ms sleep on it shows as at least
    that, and an idle event loop as far less."""
    from volren.app.timing.drive import wait
    from volren.app.timing.gestures import StallProbe

    probe = StallProbe()
    probe.start()
    wait(qapp, lambda: False, 0.05)
    time.sleep(0.2)  # the GUI thread held, as by a kernel that keeps the interpreter's lock
    wait(qapp, lambda: False, 0.05)
    assert probe.stop() >= 195.0


@pytest.mark.vtk
@pytest.mark.usefixtures("opengl")  # the 2D widget's frames: the slicer draws 2D TFs
def test_the_gesture_table_times_every_gesture_with_the_renderer_auto_picks(qapp):
    from tests.app.conftest import vtk_unusable

    if vtk_unusable():
        pytest.fail(vtk_unusable(), pytrace=False)
    from volren.app.timing import gestures as app_gestures
    from volren.samples import marschner_lobb, sample_transfer_functions

    timing = app_gestures.measure_scene(qapp, marschner_lobb(17), sample_transfer_functions()["marschner_lobb"].copy(),
                                        "ml", seconds=0.5)  # fmt: skip
    assert timing.renderer not in ("", "auto") and math.isfinite(timing.open_ms) and timing.open_ms > 0
    assert [g.gesture for g in timing.gestures] == [
        "rotate",
        "TF point",
        "crop face",
        "clip plane",
        "2D widget",
    ]
    for g in timing.gestures:
        assert g.release_ms > 0 and g.stall_ms >= 0 and 0 <= g.preview_share <= 0.25 + 1e-3, g
        assert g.still_renderer != "-"
    rows = app_gestures.markdown_rows(timing)
    assert len(rows) == 5 and all(
        r.count("|") == app_gestures.HEADER.splitlines()[0].count("|") for r in rows
    )


@pytest.mark.parametrize("args", [["--scenes", "nowhere/smooth"], ["--scenes", ","], ["--seconds", "0"]])
def test_bench_app_refuses_bad_flags_in_one_line(tmp_path, capsys, args):
    """`volren bench app` checks its flags before it opens a window."""
    from volren.cli.main import main

    (tmp_path / "data").mkdir()
    (tmp_path / "scenes").mkdir()
    assert main(["bench", "app", "--shared", str(tmp_path), *args]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("volren: error: --s"), err
