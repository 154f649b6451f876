"""`.ci/check_commit_subjects.py`: commits after the base commit keep their subjects within 72
characters (the commits before it are history); run by `.ci/run` before the set-up."""

from __future__ import annotations

import importlib.util
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SCRIPT = REPO / ".ci" / "check_commit_subjects.py"


def _module():
    spec = importlib.util.spec_from_file_location("check_commit_subjects", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


check = _module()


def _git(repo: Path, *args: str) -> str:
    return subprocess.run(
        ["git", "-C", str(repo), *args], capture_output=True, text=True, check=True
    ).stdout.strip()


def _commit(repo: Path, subject: str) -> str:
    _git(repo, "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q", "--allow-empty", "-m", subject,
         "-m", "the evidence")  # fmt: skip
    return _git(repo, "rev-parse", "HEAD")


@pytest.fixture
def repo(tmp_path: Path) -> Path:
    _git(tmp_path, "init", "-q")
    return tmp_path


def test_only_commits_after_the_base_are_checked(repo, capsys):
    _commit(repo, "An old subject from before the rule, " + "far longer than seventy-two characters" * 2)
    base = _commit(repo, "Add the rule")
    _commit(repo, "x" * 72)
    assert check.main(["--repo", str(repo), "--base", base]) == 0
    _commit(repo, "y" * 73)
    assert check.main(["--repo", str(repo), "--base", base]) == 1
    assert "73 characters: " + "y" * 73 in capsys.readouterr().err


def test_a_base_missing_from_a_full_history_fails(repo, capsys):
    _commit(repo, "Start")
    assert check.main(["--repo", str(repo), "--base", "1" * 40]) == 1
    assert "update BASE" in capsys.readouterr().err


def test_a_folder_without_git_is_not_judged(tmp_path, capsys):
    assert check.main(["--repo", str(tmp_path / "not-a-checkout"), "--base", "1" * 40]) == 0
    assert "not a git checkout" in capsys.readouterr().err


def test_the_base_is_in_this_history_and_ci_runs_the_check():
    """BASE names a commit of this repository (a shallow clone may lack it, and is not judged)."""
    problem = check.base_problem(str(REPO), check.BASE)
    assert problem is None or not problem[1], problem
    assert ".ci/check_commit_subjects.py" in (REPO / ".ci" / "run").read_text()
