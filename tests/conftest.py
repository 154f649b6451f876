"""Shared fixtures: where the shared datasets are (skipping, with an allowed reason, when they are
not) and failing early, with what to install, when OpenGL cannot work here. Which skips are
allowed and the per-session caches: tests/session_policy.py."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.session_policy import SHARED_MISSING

REPO = Path(__file__).resolve().parent.parent
SHARED = REPO.parent / "shared"
SHARED_DATA = SHARED / "data"
SHARED_SCENES = SHARED / "scenes"


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """../shared/data, or skip: the real datasets are not part of the repository."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"{SHARED_MISSING}: no datasets at {SHARED_DATA}")
    return SHARED_DATA


@pytest.fixture(scope="session")
def shared_scenes() -> Path:
    if not SHARED_SCENES.is_dir():
        pytest.skip(f"{SHARED_MISSING}: no scenes at {SHARED_SCENES}")
    return SHARED_SCENES


def load_scene_tf(name: str):
    """A transfer function from ../shared/scenes/<name>.json."""
    from volren.model.transfer_function import TransferFunction1D

    path = SHARED_SCENES / f"{name}.json"
    if not path.exists():
        pytest.skip(f"{SHARED_MISSING}: scene {path} not found")
    return TransferFunction1D.from_dict(json.loads(path.read_text()))


@pytest.fixture(scope="session")
def opengl() -> None:
    """Fail when no EGL context can be made here (the message names the packages to install):
    CI has Mesa (scripts/setup.sh installs it), so a test that needs GL must not quietly skip."""
    from volren.renderers.opengl import opengl_problem

    problem = opengl_problem()
    if problem:
        pytest.fail(problem, pytrace=False)


@pytest.fixture(scope="session")
def renders_with_vtk(opengl) -> None:
    """Requested by a test, or a fixture, that draws with the vtk renderer: what uses it is marked
    vtk and gl (tests/markers.py), and fails early, through `opengl`, where EGL cannot work."""
