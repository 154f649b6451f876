"""Markers derived from what a test uses (loaded by the repository's root conftest.py), so that a
developer can run a slice of the suite: ``pytest -m "not gl and not qt and not slow"`` is the
CPU-only part, ``pytest -m gl`` everything that needs OpenGL.

- ``qt``: the test uses pytest-qt (``qtbot``, ``qapp``), lives under tests/app (whose conftest
  imports PyQt5), or its module imports PyQt5.
- ``gl``: the test uses a fixture in `GL_FIXTURES` (``opengl`` fails early, naming what to install,
  where no EGL context can be made: a test that needs OpenGL requests it), or is marked ``vtk``.
- ``vtk``: the test uses a fixture in `VTK_FIXTURES`, or says so itself (``pytest.mark.vtk``; for
  a test parametrized by renderer, `renderer_params` marks each renderer by the backend it
  declares). VTK draws through OpenGL, hence ``gl``.
- ``slow`` is never derived: tests that take more than about 5 s carry it themselves.

The marks are checked while the tests run: a test that makes an OpenGL context (moderngl) without
the ``gl`` mark, or a VTK render window without the ``vtk`` mark, fails, so that a new test cannot
slip into the CPU-only slice. Contexts made in a subprocess are not seen, and the check is off
where a hardware GPU lets renderers that choose their backend pick OpenGL (the marks describe
what the tests use with software OpenGL, as in CI).
"""

from __future__ import annotations

import sys
from collections.abc import Iterable
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

#: Fixtures that make, or check that one can make, an OpenGL context.
GL_FIXTURES = frozenset({"opengl"})
#: Fixtures that render with the vtk renderer (tests/conftest.py; the app's windows request it).
VTK_FIXTURES = frozenset({"renders_with_vtk"})
QT_FIXTURES = frozenset({"qtbot", "qapp"})
APP_TESTS = Path(__file__).resolve().parent / "app"
#: The marks of a renderer's tests by the backend its capabilities declare (tetra's "cpu/opengl"
#: walks on the CPU unless a hardware GPU is there).
BACKEND_MARKS = {"opengl": ("gl",), "vtk": ("vtk",)}


def imports_qt(module: ModuleType | None) -> bool:
    """Whether the test module imported PyQt5 (or anything from it) at its top level."""
    for value in vars(module).values() if module is not None else ():
        name = value.__name__ if isinstance(value, ModuleType) else getattr(value, "__module__", None)
        if isinstance(name, str) and name.startswith("PyQt5"):
            return True
    return False


def derived_markers(item: pytest.Item) -> set[str]:
    """The markers `item` needs from the fixtures it uses and the module it is in."""
    fixtures = set(getattr(item, "fixturenames", ()))
    marks = {mark.name for mark in item.iter_markers()}
    derived = set()
    if (
        fixtures & QT_FIXTURES
        or item.path.is_relative_to(APP_TESTS)
        or imports_qt(getattr(item, "module", None))
    ):
        derived.add("qt")
    if fixtures & VTK_FIXTURES:
        derived.add("vtk")
    if fixtures & GL_FIXTURES or "vtk" in marks | derived:
        derived.add("gl")
    return derived - marks


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    for item in items:
        for name in sorted(derived_markers(item)):
            item.add_marker(name)


def renderer_params(names: Iterable[str]) -> list[Any]:
    """`names` of registered renderers as parameters, each marked by the backend it declares."""
    from volren.renderers.registry import registry

    params = []
    for name in names:
        marks = BACKEND_MARKS.get(registry.capabilities(name).backend, ())
        params.append(pytest.param(name, marks=[getattr(pytest.mark, mark) for mark in marks]))
    return params


# ------------------------------------------------------------------------------------ the check
#: Functions that make a context only to ask whether OpenGL works here, or what it is (cached, or
#: harmless without EGL): a test that only asks does not use OpenGL.
PROBES = frozenset({"opengl_problem", "gpu_renderer", "gl_renderer"})


class ContextWatch:
    """Records what made an OpenGL context (moderngl) or a VTK render window since `clear`."""

    def __init__(self) -> None:
        self.made: set[str] = set()

    def clear(self) -> None:
        self.made = set()

    def wrap(self, owner: Any, name: str, mark: str) -> None:
        """Make `owner.name` (a factory) record `mark` whenever something but a probe calls it."""
        original = getattr(owner, name, None)
        if original is None or getattr(original, "_watched", False):
            return

        def watched(*args: Any, **kwargs: Any) -> Any:
            if sys._getframe(1).f_code.co_name not in PROBES:
                self.made.add(mark)
            return original(*args, **kwargs)

        watched._watched = True  # type: ignore[attr-defined]
        setattr(owner, name, watched)


WATCH = ContextWatch()
UNMARKED = {
    "gl": "made an OpenGL context but is not marked gl: request the `opengl` fixture "
    '(`pytestmark = pytest.mark.usefixtures("opengl")`), or add the fixture that makes the '
    "context to GL_FIXTURES in tests/markers.py",
    "vtk": "rendered with VTK but is not marked vtk: mark it (`pytest.mark.vtk`), or add the "
    "fixture that renders to VTK_FIXTURES in tests/markers.py",
}


def pytest_sessionstart(session: pytest.Session) -> None:
    """Watch the factories every OpenGL context and VTK render window of volren's comes from."""
    import moderngl

    WATCH.wrap(moderngl, "create_standalone_context", "gl")
    try:
        from volren.renderers.vtk_mappers import _vtk
    except ImportError:  # without VTK nothing renders with it
        return
    WATCH.wrap(_vtk, "vtkEGLRenderWindow", "vtk")
    WATCH.wrap(_vtk, "vtkRenderWindow", "vtk")


def pytest_runtest_logstart(nodeid: str, location: tuple[str, int | None, str]) -> None:
    WATCH.clear()


def hardware_gpu() -> bool:
    """Whether a hardware GPU is here: renderers on `auto` may then choose OpenGL."""
    from volren.renderers.tetra.gl_walk import gpu_renderer

    return gpu_renderer() is not None


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo):
    """Fail the setup or call of a test that made a context its marks do not own up to."""
    outcome = yield
    report = outcome.get_result()
    made = ({"gl"} if WATCH.made else set()) | (WATCH.made & {"vtk"})
    missing = sorted(made - {mark.name for mark in item.iter_markers()})
    if missing and report.passed and call.when != "teardown" and not hardware_gpu():
        report.outcome = "failed"
        report.longrepr = "\n".join(f"{item.nodeid} {UNMARKED[name]}" for name in missing)
        WATCH.clear()
