"""Fixtures for the desktop-app tests: offscreen Qt, a small window, fake renderers, a sample.

Qt must be told to run offscreen before the QApplication exists, hence the environment is set at
import time (pytest imports conftest files before any fixture creates the application).
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable, Iterator, Mapping
from typing import Any, ClassVar

os.environ["QT_QPA_PLATFORM"] = "offscreen"
os.environ.setdefault("XDG_RUNTIME_DIR", tempfile.mkdtemp(prefix="volren-xdg-"))
# QSettings (recent files) must never touch the person's own configuration.
os.environ["XDG_CONFIG_HOME"] = tempfile.mkdtemp(prefix="volren-config-")

# Qt and pytest-qt are test dependencies (.[test,app,bench]): without them these tests fail, not skip.
import numpy as np  # noqa: E402
import pytest  # noqa: E402
import pytestqt  # noqa: E402, F401
from PyQt5 import QtWidgets  # noqa: E402, F401

from volren.app.core.loading import LoadedInput  # noqa: E402
from volren.app.core.state import ViewState, default_camera  # noqa: E402
from volren.app.tf_editor.history import TFHistory  # noqa: E402
from volren.errors import VolrenError  # noqa: E402
from volren.model.volume import UniformVolume  # noqa: E402
from volren.renderers.base import Capabilities, KindSupport, OptionSpec, RendererBase  # noqa: E402
from volren.renderers.registry import registry  # noqa: E402
from volren.samples import marschner_lobb, sample_transfer_functions  # noqa: E402

#: Room for the docks (TF editors, settings) and a viewport of about 500 x 600 pixels.
WINDOW_SIZE = (1300, 700)
#: Generous: the first VTK frame creates an EGL context; later frames take tens of ms.
FRAME_TIMEOUT_MS = 20000


_vtk_reason: list[str | None] = []


def vtk_unusable() -> str | None:
    """Why the vtk renderer cannot draw here (no EGL, ...), or None; checked once."""
    if not _vtk_reason:
        try:
            with registry.create("vtk") as r:
                r.set_volume(marschner_lobb(5))
                r.set_transfer_function(sample_transfer_functions()["marschner_lobb"])
                from volren.model.camera import Camera

                r.render(Camera.orbit(r.volume.bounds), 4, 4)
            _vtk_reason.append(None)
        except Exception as exc:  # noqa: BLE001
            _vtk_reason.append(f"the vtk renderer cannot render here: {exc}")
    return _vtk_reason[0]


@pytest.fixture(scope="session")
def ml_volume() -> UniformVolume:
    return marschner_lobb()


@pytest.fixture
def sample(ml_volume) -> LoadedInput:
    """The Marschner-Lobb sample built in memory (no file reading needed)."""
    return LoadedInput(ml_volume, sample_transfer_functions()["marschner_lobb"], source="marschner_lobb")


@pytest.fixture
def state() -> ViewState:
    """A view state holding the Marschner-Lobb sample (17 points a side) and its TF; the TF editor
    tests edit it (modules with other scenes define their own `state`)."""
    s = ViewState()
    volume = marschner_lobb(17)
    s.load(volume, sample_transfer_functions()["marschner_lobb"].copy(), default_camera(volume))
    return s


@pytest.fixture
def history(state) -> Iterator[TFHistory]:
    """The undo history of `state`'s TF edits, detached afterwards."""
    h = TFHistory(state)
    yield h
    h.detach()


@pytest.fixture
def ini(tmp_path):
    """Settings in a temporary INI file (the app's own store is never touched)."""
    from PyQt5.QtCore import QSettings

    return QSettings(str(tmp_path / "volren-test.ini"), QSettings.IniFormat)


@pytest.fixture
def error_boxes(monkeypatch) -> list[tuple[str, str]]:
    """Record QMessageBox.critical calls instead of opening a modal box; questions (closing with a
    job still running, when pytest-qt closes the test's windows) are answered Yes unless a test
    patches them itself."""
    from PyQt5.QtWidgets import QMessageBox

    calls: list[tuple[str, str]] = []

    def critical(parent, title, text, *args, **kwargs):
        calls.append((title, text))
        return QMessageBox.Ok

    monkeypatch.setattr(QMessageBox, "question", lambda *args, **kwargs: QMessageBox.Yes)

    monkeypatch.setattr(QMessageBox, "critical", critical)
    return calls


@pytest.fixture
def make_window(qtbot, error_boxes, renders_with_vtk) -> Iterator[Callable[..., Any]]:
    """Build shown MainWindows (closed and shut down after the test)."""
    from volren.app.window.main_window import MainWindow

    reason = vtk_unusable()
    if reason:  # CI can render with VTK (Mesa through EGL): a window test must not quietly skip
        pytest.fail(reason, pytrace=False)
    made = []

    def make(**kwargs: Any) -> MainWindow:
        w = MainWindow(**kwargs)
        w.resize(*WINDOW_SIZE)
        qtbot.addWidget(w)
        w.show()
        made.append(w)
        return w

    yield make
    for w in made:
        w.shutdown()


@pytest.fixture
def window(make_window):
    return make_window()


@pytest.fixture
def loaded_window(window, sample, qtbot):
    """A window showing the sample with the vtk renderer, first full frame already on screen and
    the previews' renderer set up."""
    with qtbot.waitSignal(window.fullFrameShown, timeout=FRAME_TIMEOUT_MS):
        window.files.apply_loaded(sample, "vtk")
    # the previews' renderer is set up next, while the view is still: gestures start after it
    qtbot.waitUntil(lambda: not window.service.warming, timeout=FRAME_TIMEOUT_MS)
    return window


# ---------------------------------------------------------------------------- fake renderers
class FakeRenderer(RendererBase):
    """A constant-colour renderer that records what it was given (and on which thread)."""

    name: ClassVar[str] = "fake"
    capabilities: ClassVar[Capabilities] = Capabilities(
        kinds={"uniform": KindSupport()}, summary="test double"
    )
    color: ClassVar[tuple[float, float, float, float]] = (0.4, 0.2, 0.1, 0.5)
    calls: ClassVar[list[dict[str, Any]]] = []

    def _render(self, camera, width, height, progress) -> tuple[np.ndarray, Mapping[str, float]]:
        type(self).calls.append(
            {"camera": camera, "tf": self.transfer_function.copy(), "size": (width, height)}
        )
        image = np.empty((height, width, 4), np.float32)
        image[...] = self.color
        return image, {}


class TetOnlyRenderer(FakeRenderer):
    name: ClassVar[str] = "fake_tet_only"
    capabilities: ClassVar[Capabilities] = Capabilities(kinds={"tet": KindSupport()}, summary="tet only")


class SlowSetupRenderer(FakeRenderer):
    """Takes `setup_s` to take a volume (a large mesh's preparation, an octree)."""

    name: ClassVar[str] = "fake_slow_setup"
    setup_s: ClassVar[float] = 0.8

    def _volume_changed(self) -> None:
        import time

        time.sleep(self.setup_s)


class DragOptionsRenderer(FakeRenderer):
    """Has a table-size option and asks for a small table while a TF is dragged."""

    name: ClassVar[str] = "fake_drag"
    capabilities: ClassVar[Capabilities] = Capabilities(
        kinds={"uniform": KindSupport()}, summary="test double", tf_drag_options={"table_size": 8}
    )
    options: ClassVar[tuple[OptionSpec, ...]] = (OptionSpec("table_size", 256, "int", "entries", low=2),)


class OutsideOnlyRenderer(FakeRenderer):
    """Cannot draw a perspective view from inside the volume (as shearwarp)."""

    name: ClassVar[str] = "fake_outside_only"
    capabilities: ClassVar[Capabilities] = Capabilities(kinds={"uniform": KindSupport(eye_inside=False)},
                                                        summary="no eye inside")  # fmt: skip


class BrokenRenderer(FakeRenderer):
    name: ClassVar[str] = "fake_broken"

    def _render(self, camera, width, height, progress):
        raise VolrenError("fake_broken: the shader did not compile\n(line 3)")


@pytest.fixture
def fake_renderers() -> Iterator[dict[str, type]]:
    """Register the fake renderers in-process; unregistered afterwards."""
    classes = {cls.name: cls for cls in (FakeRenderer, TetOnlyRenderer, BrokenRenderer, SlowSetupRenderer,
                                         DragOptionsRenderer, OutsideOnlyRenderer)}  # fmt: skip
    FakeRenderer.calls.clear()
    for name, cls in classes.items():
        registry.register(name, cls, replace=True)
    try:
        yield classes
    finally:
        for name in classes:
            registry.unregister(name)


@pytest.fixture
def fake_2d(fake_renderers) -> Iterator[type]:
    """The constant-colour fake renderer drawing 2D TFs too, registered as "fake_2d" (with the
    other fakes); unregistered afterwards."""

    class Fake2D(fake_renderers["fake"]):
        name: ClassVar[str] = "fake_2d"
        capabilities: ClassVar[Capabilities] = Capabilities(
            kinds={"uniform": KindSupport(tf_dims=frozenset({1, 2}))}, summary="test double, 1D and 2D TFs"
        )

    registry.register(Fake2D.name, Fake2D, replace=True)
    try:
        yield Fake2D
    finally:
        registry.unregister(Fake2D.name)
