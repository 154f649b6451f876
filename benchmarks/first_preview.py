"""`python -m benchmarks.first_preview`: how long the first gesture after opening a volume waits.

Why: the app's previews are drawn by the renderer measured fastest at `interactive` (shearwarp
on uniform grids), usually another renderer than the still frames'; the first preview used to
pay that renderer's set-up (its imports, its per-volume structures, its first tables). Now the
render thread sets it up while the view is still (`RenderService.warm`). For each dataset this
opens a fresh window at VIEWPORT, waits for the first full frame (and, when warming, for the
warm-up), then starts a rotation and times the first preview to come; median of `--repeats`
fresh windows, warm-up on and off in the same run.

    QT_QPA_PLATFORM=offscreen .venv/bin/python -m benchmarks.first_preview --shared ../shared
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

VIEWPORT = (800, 600)
DATASETS = {
    "bonsai": "uniform/bonsai.vti",
    "engine": "uniform/engine.vti",
    "oxygen": "tets/oxygen_post_tets.vtu",
}


def _wait(app, condition, timeout_s: float = 120.0) -> float:
    start = time.perf_counter()
    while not condition():
        if time.perf_counter() - start > timeout_s:
            raise TimeoutError("timed out")
        app.processEvents()
        time.sleep(0.001)
    return time.perf_counter() - start


def first_preview_ms(app, loaded, warm: bool) -> tuple[float, str, str]:
    """(ms from the start of a rotation to its first preview, the still frames' renderer, the
    preview's renderer)."""
    from volren.app.window.main_window import MainWindow

    window = MainWindow()
    window.show_error_dialogs = False
    if not warm:
        window.service.warm = lambda *args, **kwargs: None  # the set-up left to the first preview
    window.viewport.setFixedSize(*VIEWPORT)
    window.show()
    frames = []
    window.frameShown.connect(frames.append)
    try:
        window.files.apply_loaded(loaded)
        _wait(app, lambda: any(f.full for f in frames))
        _wait(app, lambda: not window.service.warming)
        count = len(frames)
        state = window.state
        state.begin_interaction()
        state.set_camera(state.camera.azimuth(5.0))
        seconds = _wait(app, lambda: len(frames) > count)
        state.end_interaction()
        return seconds * 1000.0, state.renderer, frames[count].renderer
    finally:
        window.shutdown()
        window.deleteLater()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shared", default=str(Path(__file__).resolve().parents[2] / "shared"))
    parser.add_argument("--datasets", default=",".join(DATASETS))
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    from PyQt5.QtWidgets import QApplication

    app = QApplication([])
    from volren.app.core.loading import load_input

    print(f"first preview after opening, {VIEWPORT[0]}x{VIEWPORT[1]}, median of {args.repeats} fresh windows")
    print(
        "| dataset | still renderer | preview renderer | set up at the first preview, ms | set up while still, ms | ratio |"
    )
    print("|---|---|---|---|---|---|")
    for name in args.datasets.split(","):
        loaded = load_input(Path(args.shared) / "data" / DATASETS[name])
        cold, warm = [], []
        still = previewer = ""
        for _ in range(args.repeats):
            ms, still, previewer = first_preview_ms(app, loaded, warm=False)
            cold.append(ms)
            warm.append(first_preview_ms(app, loaded, warm=True)[0])
        c, w = statistics.median(cold), statistics.median(warm)
        print(f"| {name} | {still} (auto) | {previewer} | {c:.0f} | {w:.0f} | {c / w:.1f}x |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
