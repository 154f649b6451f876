"""Where the benchmarks find the shared datasets: --shared, else $VOLREN_SHARED, never a path
relative to the installed package."""

from __future__ import annotations

import pytest

from volren.bench.datasets import SHARED_ENV, shared_folder
from volren.cli.main import main
from volren.errors import VolrenError


def make_shared(root):
    (root / "data").mkdir(parents=True)
    (root / "scenes").mkdir()
    return root


def test_the_flag_wins_over_the_environment(tmp_path, monkeypatch):
    flag, env = make_shared(tmp_path / "flag"), make_shared(tmp_path / "env")
    monkeypatch.setenv(SHARED_ENV, str(env))
    assert shared_folder(str(flag)) == flag
    assert shared_folder(None) == env


def test_without_either_it_is_an_error_or_none(monkeypatch):
    monkeypatch.delenv(SHARED_ENV, raising=False)
    with pytest.raises(VolrenError, match=SHARED_ENV):
        shared_folder(None)
    assert shared_folder(None, required=False) is None


def test_a_folder_without_data_and_scenes_is_named(tmp_path, monkeypatch):
    monkeypatch.setenv(SHARED_ENV, str(tmp_path))
    assert shared_folder(None, required=False) is None  # a stale variable: samples only
    with pytest.raises(VolrenError, match=str(tmp_path)):
        shared_folder(str(tmp_path), required=False)  # but a flag given by hand must be right


def test_bench_app_without_a_shared_folder_says_how_to_give_one(monkeypatch, capsys):
    monkeypatch.delenv(SHARED_ENV, raising=False)
    assert main(["bench", "app"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--shared" in err[0] and SHARED_ENV in err[0]
