"""tests/markers.py: the markers derived from what a test uses (checked on a throw-away test folder
in a subprocess, as tests/test_session_policy.py does), and the check that fails a test making an
OpenGL context without the `gl` mark."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.markers import renderer_params

REPO = Path(__file__).resolve().parents[1]

USES = '''
import pytest


@pytest.fixture(scope="session")
def opengl():
    """Stands in for tests/conftest.py's fixture: its name is what marks a test."""


@pytest.fixture(scope="session")
def renders_with_vtk(opengl):
    pass


@pytest.fixture
def window(renders_with_vtk):
    pass


def test_cpu():
    pass


def test_asks_for_opengl(opengl):
    pass


def test_through_a_fixture(window):
    pass


@pytest.mark.vtk
def test_marked_vtk():
    pass


def test_qtbot(qtbot):
    pass
'''

IMPORTS_QT = """
from PyQt5.QtCore import QObject


def test_in_a_module_that_imports_qt():
    pass
"""

CONTEXTS = """
import moderngl
import pytest


def make_context():
    moderngl.create_standalone_context(backend="egl").release()


def test_unmarked_context():
    make_context()


@pytest.mark.gl
def test_marked_context():
    make_context()


def test_only_asks_whether_opengl_works():
    from volren.renderers.opengl import opengl_problem

    assert opengl_problem() is None
"""


def run_pytest(folder: Path, *args: str) -> subprocess.CompletedProcess:
    (folder / "pytest.ini").write_text("[pytest]\n")
    cmd = [sys.executable, "-m", "pytest", "-p", "tests.markers", "-p", "no:cacheprovider", "-q",
           "-c", str(folder / "pytest.ini"), "--rootdir", str(folder), *args, str(folder)]  # fmt: skip
    return subprocess.run(cmd, capture_output=True, text=True, timeout=120, cwd=REPO)


#: Prints each collected test's marks of interest (after tests.markers has added its own).
REPORT_MARKS = """
def pytest_collection_finish(session):
    for item in session.items:
        marks = sorted({mark.name for mark in item.iter_markers()} & {"gl", "vtk", "qt", "slow"})
        print("MARKS", item.name, *marks)
"""


def test_marks_follow_the_fixtures_and_imports(tmp_path):
    (tmp_path / "test_uses.py").write_text(USES)
    (tmp_path / "test_imports_qt.py").write_text(IMPORTS_QT)
    (tmp_path / "conftest.py").write_text(REPORT_MARKS)
    result = run_pytest(tmp_path, "--collect-only")
    assert result.returncode == 0, result.stdout + result.stderr
    marks = {
        words[1]: set(words[2:])
        for words in map(str.split, result.stdout.splitlines())
        if words[:1] == ["MARKS"]
    }
    assert marks == {
        "test_cpu": set(),
        "test_asks_for_opengl": {"gl"},
        "test_through_a_fixture": {"gl", "vtk"},
        "test_marked_vtk": {"gl", "vtk"},
        "test_qtbot": {"qt"},
        "test_in_a_module_that_imports_qt": {"qt"},
    }


def test_renderers_are_marked_by_their_backend():
    params = renderer_params(["vtk", "slicer", "raycast"])
    marks = {param.values[0]: {mark.name for mark in param.marks} for param in params}
    assert marks == {"vtk": {"vtk"}, "slicer": {"gl"}, "raycast": set()}


@pytest.mark.usefixtures("opengl")
def test_a_context_made_without_the_gl_mark_fails_the_test(tmp_path):
    (tmp_path / "test_contexts.py").write_text(CONTEXTS)
    result = run_pytest(tmp_path, "-rA")
    out = result.stdout
    assert result.returncode == 1, out
    assert out.strip().splitlines()[-1].startswith("1 failed, 2 passed"), out
    assert "test_contexts.py::test_unmarked_context made an OpenGL context but is not marked gl" in out
    # pytest appends " - <message>" to the summary line only when the terminal is wide enough.
    failed = re.compile(r"^FAILED \S+::test_unmarked_context( - .*)?$")
    assert any(failed.match(line) for line in out.splitlines()), out
