"""`benchmarks.step_search`: the search's time is the renderer's own count for a frame with a new TF."""

from __future__ import annotations

from benchmarks import step_search
from volren.samples import sample_paths


def test_a_new_tfs_frame_reports_its_search_within_its_time(tmp_path, monkeypatch):
    monkeypatch.setenv("VOLREN_STEP_CACHE", str(tmp_path))  # searched, not read back
    volume, tf = sample_paths("marschner_lobb")
    found = step_search.search_share(volume, tf, None, repeats=2)
    assert found is not None  # the default level targets an error on this smooth TF
    frame_ms, search_ms, step = found
    assert 0.0 < search_ms < frame_ms and 0.0 < step <= 2.0
