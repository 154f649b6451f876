"""Opening a headerless raw file in the app (issue 23): the dialog guesses a shape from the file's
size, accepts only a layout that matches the file exactly, and the volume opens with it."""

from __future__ import annotations

import numpy as np
from PyQt5.QtWidgets import QDialogButtonBox

from tests.app.conftest import FRAME_TIMEOUT_MS
from volren.app.files.raw_dialog import RawDialog, guess_shape


def test_the_guess_is_a_cube_of_the_smallest_sample_type_that_fits() -> None:
    assert guess_shape(16**3) == ("uint8", (16, 16, 16))
    assert guess_shape(2 * 15**3) == ("uint16", (15, 15, 15))
    assert guess_shape(7) is None


def test_the_dialog_accepts_only_a_layout_of_the_files_size(qtbot, tmp_path) -> None:
    path = tmp_path / "scan.raw"
    (np.arange(20 * 30 * 40, dtype=">u2")).tofile(path)  # 48,000 bytes: no cube of any type
    dialog = RawDialog(path)
    qtbot.addWidget(dialog)
    ok = dialog.buttons.button(QDialogButtonBox.Ok)
    assert not ok.isEnabled() and "no match" in dialog.check.text() and "48,000" in dialog.check.text()
    for box, n in zip(dialog.shape, (20, 30, 40), strict=True):
        box.setValue(n)
    dialog.dtype.setCurrentText("uint16")
    assert ok.isEnabled()
    dialog.byte_order.setCurrentText("big")
    dialog.spacing[2].setValue(2.5)
    assert dialog.parameters() == {"shape": (20, 30, 40), "dtype": "uint16", "byte_order": "big",
                                   "spacing": (1.0, 1.0, 2.5), "header_bytes": 0}  # fmt: skip
    dialog.header.setValue(2)
    assert not ok.isEnabled()


def test_opening_a_raw_file_asks_its_layout_and_shows_it(make_window, qtbot, tmp_path, monkeypatch) -> None:
    path = tmp_path / "scan.raw"
    values = np.arange(12 * 10 * 8, dtype=np.float32).reshape(8, 10, 12)
    values.tofile(path)
    w = make_window()
    asked = []

    def answer(p):
        asked.append(p)
        return {"shape": (12, 10, 8), "dtype": "float32", "byte_order": "little", "spacing": (1.0, 1.0, 2.0),
                "header_bytes": 0}  # fmt: skip

    monkeypatch.setattr(w.files, "ask_raw_layout", answer)
    with qtbot.waitSignal(w.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        w.files.open_input(str(path))
    assert asked == [str(path)]
    volume = w.state.volume
    assert volume.dimensions == (12, 10, 8) and tuple(volume.spacing) == (1.0, 1.0, 2.0)
    np.testing.assert_array_equal(volume.values, values)
    # cancelled: nothing is loaded, what is shown stays
    monkeypatch.setattr(w.files, "ask_raw_layout", lambda p: None)
    w.files.open_input(str(path))
    assert w.state.volume is volume and not w.files.loader.busy
