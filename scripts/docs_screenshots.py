"""The app's screenshots in docs/ (the README shows them): bonsai in the 1D and the 2D editor,
with the shared scenes' "smooth" TF, and the 2D TF seeded from it.

    QT_QPA_PLATFORM=offscreen .venv/bin/python scripts/docs_screenshots.py [--shared ../shared]

Renders with the app's defaults (renderer auto at the `interactive` level), waits for the full
frame, and grabs the whole window at 1500x820.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

WINDOW = (1500, 820)


def _wait(app, condition, timeout_s: float = 120.0) -> None:
    end = time.monotonic() + timeout_s
    while not condition():
        if time.monotonic() > end:
            raise TimeoutError("no full frame")
        app.processEvents()
        time.sleep(0.01)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shared", default=str(Path(__file__).resolve().parents[2] / "shared"))
    parser.add_argument("--out", default=str(Path(__file__).resolve().parents[1] / "docs"))
    args = parser.parse_args()
    from PyQt5.QtWidgets import QApplication

    app = QApplication([])
    from volren.app.core.loading import load_input
    from volren.app.window.main_window import MainWindow

    window = MainWindow()
    window.show_error_dialogs = False
    window.resize(*WINDOW)
    window.show()
    shown = []
    window.fullFrameShown.connect(shown.append)
    shared = Path(args.shared)
    window.files.apply_loaded(
        load_input(shared / "data/uniform/bonsai.vti", shared / "scenes/bonsai-smooth.json")
    )
    _wait(app, lambda: bool(shown) and not window.service.warming)
    window.overlay_actions["legend"].setChecked(True)
    app.processEvents()
    window.grab().save(str(Path(args.out) / "app-1d-editor.png"))
    panel = window.docks.tf_panel
    panel.tabs.setCurrentWidget(panel.editor_2d)
    count = len(shown)
    panel.editor_2d.use_2d_button.click()
    _wait(app, lambda: len(shown) > count and shown[-1].serial == window.service.latest_serial)
    app.processEvents()
    window.grab().save(str(Path(args.out) / "app-2d-editor.png"))
    window.shutdown()
    print(f"wrote {args.out}/app-1d-editor.png and app-2d-editor.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
