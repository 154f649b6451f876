"""`volren view --screenshot` end to end, in a subprocess: a real X window under Xvfb, and errors."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.qt


XVFB_PACKAGES = (
    "xvfb xauth libxkbcommon-x11-0 libxcb-icccm4 libxcb-image0 libxcb-keysyms1 libxcb-render-util0 "
    "libxcb-shape0 libxcb-xinerama0 libdbus-1-3 libfontconfig1 libglib2.0-0"
)


def view(args: list[str], env: dict[str, str], prefix: list[str] = ()) -> subprocess.CompletedProcess:
    cmd = [*prefix, sys.executable, "-m", "volren.cli.main", "view", *args]
    return subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=240)


def chromatic_fraction(path: Path) -> float:
    """Share of pixels with clearly coloured (not grey) values: the UI and background are grey."""
    from PIL import Image

    rgb = np.asarray(Image.open(path).convert("RGB")).astype(int)
    return float(np.mean(rgb.max(axis=-1) - rgb.min(axis=-1) > 40))


@pytest.mark.xvfb
def test_view_screenshot_of_a_real_x_window(tmp_path):
    if shutil.which("xvfb-run") is None:
        pytest.fail(
            f"xvfb-run is not on PATH (scripts/setup.sh --tests installs {XVFB_PACKAGES})", pytrace=False
        )
    out = tmp_path / "view.png"
    env = dict(os.environ, QT_QPA_PLATFORM="xcb")
    result = view(["--screenshot", str(out)], env, prefix=["xvfb-run", "-a", "-s", "-screen 0 1280x1024x24"])
    assert result.returncode == 0, f"exit {result.returncode}: {result.stderr[-2000:]}"
    from PIL import Image

    with Image.open(out) as image:
        assert image.format == "PNG" and image.width >= 400 and image.height >= 300
    assert chromatic_fraction(out) > 0.02, "the screenshot shows no rendered volume"


@pytest.mark.xvfb
@pytest.mark.vtk
def test_a_tf_edit_in_the_real_window_changes_the_frame_on_screen():
    """A real X window: a click in the 1D editor adds an opaque point, and the pixels the window
    system shows in the viewport change (grabbed from the screen, not from the widget)."""
    import json

    if shutil.which("xvfb-run") is None:
        pytest.fail(
            f"xvfb-run is not on PATH (scripts/setup.sh --tests installs {XVFB_PACKAGES})", pytrace=False
        )
    env = dict(os.environ, QT_QPA_PLATFORM="xcb")
    cmd = [
        "xvfb-run",
        "-a",
        "-s",
        "-screen 0 1400x900x24",
        sys.executable,
        "-m",
        "tests.app.real_window_edit",
    ]
    root = Path(__file__).resolve().parents[2]
    result = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=240, cwd=root)
    assert result.returncode == 0, f"exit {result.returncode}: {result.stderr[-2000:]}"
    report = json.loads(result.stdout.strip().splitlines()[-1])
    assert report["platform"] == "xcb"
    assert report["points_added"] == 1
    assert report["changed_fraction"] > 0.02, report
    assert report["frame_matches_screen"], report
    assert report["round_trip"] == [2, True, True], (
        report
    )  # the 1D TF as a 2D band, then the edited 1D TF back
    enabled, tooltip, dims, _status = report["mesh_2d"]
    assert (
        not enabled
        and "No renderer draws 2D transfer functions on tetrahedral volumes" in tooltip
        and dims == 1
    )


def test_view_with_an_unknown_renderer_fails_in_one_line(tmp_path):
    env = dict(os.environ, QT_QPA_PLATFORM="offscreen")
    result = view(["--renderer", "no_such_renderer", "--screenshot", str(tmp_path / "x.png")], env)
    assert result.returncode == 1
    assert result.stderr.strip().count("\n") == 0 and "no_such_renderer" in result.stderr
    assert not (tmp_path / "x.png").exists()


def test_view_screenshot_of_a_missing_file_fails_in_one_line(tmp_path):
    env = dict(os.environ, QT_QPA_PLATFORM="offscreen")
    result = view([str(tmp_path / "missing.vti"), "--screenshot", str(tmp_path / "x.png")], env)
    assert result.returncode == 1
    lines = [line for line in result.stderr.splitlines() if line.startswith("volren:")]
    assert len(lines) == 1 and "missing.vti" in lines[0], result.stderr
    assert not (tmp_path / "x.png").exists()


def test_view_screenshot_of_a_raw_file_says_how_to_give_its_layout(tmp_path):
    """No dialog where nobody can answer it: a one-line error naming the file and the flags."""
    raw = tmp_path / "scan.raw"
    raw.write_bytes(bytes(4096))
    env = dict(os.environ, QT_QPA_PLATFORM="offscreen")
    result = view([str(raw), "--screenshot", str(tmp_path / "x.png")], env)
    assert result.returncode == 1
    lines = [line for line in result.stderr.splitlines() if line.startswith("volren:")]
    assert len(lines) == 1 and "scan.raw" in lines[0] and "--raw-shape" in lines[0], result.stderr
    assert not (tmp_path / "x.png").exists()
