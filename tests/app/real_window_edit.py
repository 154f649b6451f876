"""Run under Xvfb by test_app_cli_view: the real window, a TF edit through the 1D editor with
real mouse events, and the pixels on screen before and after (printed as one JSON line)."""

from __future__ import annotations

import json
import sys
import time

import numpy as np
from PyQt5.QtCore import QPoint, Qt
from PyQt5.QtTest import QTest
from PyQt5.QtWidgets import QApplication


def screen_pixels(widget) -> np.ndarray:
    """What the window system shows of `widget` (grabbed from the screen, not re-rendered)."""
    screen = QApplication.primaryScreen()
    origin = widget.mapToGlobal(QPoint(0, 0))
    image = screen.grabWindow(0, origin.x(), origin.y(), widget.width(), widget.height()).toImage()
    image = image.convertToFormat(image.Format_RGB888)
    data = np.frombuffer(image.constBits().asstring(image.byteCount()), np.uint8)
    return data.reshape(image.height(), image.bytesPerLine())[:, : 3 * image.width()].reshape(
        image.height(), image.width(), 3
    )


def main() -> int:
    app = QApplication(sys.argv[:1])
    from volren.app.core.loading import load_input
    from volren.app.window.main_window import MainWindow

    window = MainWindow()
    window.show_error_dialogs = False
    window.resize(1300, 760)
    window.show()
    full = []
    window.fullFrameShown.connect(full.append)

    def wait_full(count: int, timeout_s: float = 60.0) -> None:
        end = time.time() + timeout_s
        while len(full) < count and time.time() < end:
            app.processEvents()
            time.sleep(0.005)
        if len(full) < count:
            raise TimeoutError("no full-quality frame")
        for _ in range(20):  # let the repaint reach the screen
            app.processEvents()
            time.sleep(0.01)

    for action in window.overlay_actions.values():  # the frame alone is compared with the screen
        action.setChecked(False)
    window.files.apply_loaded(load_input(None), "vtk")
    wait_full(1)
    before = screen_pixels(window.viewport)
    curve = window.docks.tf_panel.editor_1d.curve
    lo, hi = window.state.volume.value_range
    points_before = len(window.state.transfer_function.opacity_points)
    QTest.mouseClick(curve, Qt.LeftButton, Qt.NoModifier, curve.position_of(lo + 0.6 * (hi - lo), 1.0))
    wait_full(2)
    after = screen_pixels(window.viewport)
    result = {
        "platform": app.platformName(),
        "viewport": [window.viewport.width(), window.viewport.height()],
        "points_added": len(window.state.transfer_function.opacity_points) - points_before,
        "changed_fraction": float(np.mean(np.abs(after.astype(int) - before).max(axis=-1) > 10)),
        "frame_matches_screen": bool(
            np.abs(after.astype(int) - full[-1].rgb[: after.shape[0], : after.shape[1]]).max() <= 2
            if full[-1].rgb.shape[:2] == after.shape[:2]
            else False
        ),
    }
    # issue 23: 1D -> 2D -> 1D through the tabs' buttons keeps the edited TFs; a mesh offers no 2D TF
    panel = window.docks.tf_panel
    edited_1d = window.state.transfer_function
    panel.tabs.setCurrentIndex(1)
    QTest.mouseClick(panel.editor_2d.use_2d_button, Qt.LeftButton)
    wait_full(3)
    seeded = window.state.transfer_function
    panel.tabs.setCurrentIndex(0)
    QTest.mouseClick(panel.editor_1d.use_1d_button, Qt.LeftButton)
    wait_full(4)
    result["round_trip"] = [seeded.dims, [w.type for w in seeded.widgets] == ["1d"],
                            window.state.transfer_function is edited_1d]  # fmt: skip
    window.files.apply_loaded(load_input("data_samples/hollow_cylinder.vtu"), "tetra")
    wait_full(5)
    panel.tabs.setCurrentIndex(1)
    button = panel.editor_2d.use_2d_button
    QTest.mouseClick(button, Qt.LeftButton)  # disabled: nothing happens
    app.processEvents()
    result["mesh_2d"] = [button.isEnabled(), button.toolTip(), window.state.transfer_function.dims,
                         window.statusBar().currentMessage()]  # fmt: skip
    print(json.dumps(result))
    window.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
