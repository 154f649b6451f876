"""The step raycast's error target chose, stored on disk per scene (`volren.renderers.raycast.step_cache`):
a later renderer (a later process) reads it instead of searching, and gets the same image."""

from __future__ import annotations

import numpy as np
import pytest

from tests.renderers.test_raycast import SHELL_TF, SMOOTH_TF, draw, field
from volren.model import Camera, UniformVolume
from volren.renderers.raycast import renderer as raycast_module
from volren.renderers.raycast import step_cache

OPTIONS = {"target_error": 0.005}


@pytest.fixture
def cache(tmp_path, monkeypatch):
    folder = tmp_path / "steps"
    monkeypatch.setenv(step_cache.CACHE_ENV, str(folder))
    return folder


@pytest.fixture
def searches(monkeypatch):
    """The number of step searches run so far (a list of one count)."""
    count = [0]
    search = raycast_module.largest_step_within

    def counted(*args, **kwargs):
        count[0] += 1
        return search(*args, **kwargs)

    monkeypatch.setattr(raycast_module, "largest_step_within", counted)
    return count


def camera_for(volume: UniformVolume) -> Camera:
    return Camera.orbit(volume.bounds, 30, 20, zoom=1.2)


def test_a_cached_step_gives_the_searched_step_and_the_same_image(cache, searches):
    volume = field()
    first, searched = draw(volume, SHELL_TF, camera_for(volume), step=1.0, options=OPTIONS)
    assert searches[0] == 1 and len(list(cache.glob("*.json"))) == 1
    second, cached = draw(volume, SHELL_TF, camera_for(volume), step=1.0, options=OPTIONS)
    assert searches[0] == 1  # read, not searched
    for name in ("step", "step_relative_error"):
        assert cached.last_frame.counters[name] == searched.last_frame.counters[name]
    assert searched.last_frame.counters["step"] < 1.0  # a step the search chose, not the coarsest
    assert np.array_equal(first, second)


def test_another_tf_volume_view_or_target_searches_again(cache, searches):
    volume = field()
    camera = camera_for(volume)
    draw(volume, SHELL_TF, camera, step=1.0, options=OPTIONS)
    draw(volume, SMOOTH_TF, camera, step=1.0, options=OPTIONS)
    assert searches[0] == 2
    values = volume.values.copy()
    values[3, 4, 5] += 0.25  # one value of 4032
    changed = UniformVolume(values, spacing=volume.spacing)
    draw(changed, SHELL_TF, camera, step=1.0, options=OPTIONS)
    assert searches[0] == 3
    draw(UniformVolume(volume.values, spacing=(1.0, 1.0, 1.1)), SHELL_TF, camera, step=1.0, options=OPTIONS)
    assert searches[0] == 4
    draw(volume, SHELL_TF, Camera.orbit(volume.bounds, 75, 10, zoom=1.2), step=1.0, options=OPTIONS)
    assert searches[0] == 5
    draw(volume, SHELL_TF, camera, step=1.0, options={"target_error": 0.01})
    assert searches[0] == 6
    draw(volume, SHELL_TF, camera, step=1.0, preintegration=True, options=OPTIONS)
    assert searches[0] == 7
    assert len(list(cache.glob("*.json"))) == 7
    draw(changed, SHELL_TF, camera, step=1.0, options=OPTIONS)
    assert searches[0] == 7


@pytest.mark.parametrize("content", [b"", b"{not json", b'{"format": 1, "key": "other", "step": 0.5, "error": 0.0}',
                                     b'{"format": 1, "step": -1}', b"\xff\xfe\x00"])  # fmt: skip
def test_a_corrupt_entry_is_searched_again_and_replaced(cache, searches, content):
    volume = field()
    first, searched = draw(volume, SHELL_TF, camera_for(volume), step=1.0, options=OPTIONS)
    (entry,) = cache.glob("*.json")
    entry.write_bytes(content)
    second, again = draw(volume, SHELL_TF, camera_for(volume), step=1.0, options=OPTIONS)
    assert searches[0] == 2
    assert again.last_frame.counters["step"] == searched.last_frame.counters["step"]
    assert np.array_equal(first, second)
    assert step_cache.read(entry.stem) is not None  # rewritten whole


def test_a_cache_folder_that_cannot_be_written_leaves_the_search_uncached(tmp_path, monkeypatch, searches):
    blocker = tmp_path / "a-file"
    blocker.write_text("not a folder")
    monkeypatch.setenv(step_cache.CACHE_ENV, str(blocker / "steps"))  # mkdir fails: the parent is a file
    volume = field()
    first, _ = draw(volume, SHELL_TF, camera_for(volume), step=1.0, options=OPTIONS)
    second, _ = draw(volume, SHELL_TF, camera_for(volume), step=1.0, options=OPTIONS)
    assert searches[0] == 2
    assert np.array_equal(first, second)
    assert list(tmp_path.iterdir()) == [blocker]


def test_no_temporary_files_are_left_behind(cache):
    step_cache.write("k" * 64, 0.5, 0.001)
    assert [p.name for p in cache.iterdir()] == ["k" * 64 + ".json"]
    assert step_cache.read("k" * 64) == (0.5, 0.001)


def test_the_volume_digest_covers_every_byte_and_the_shape(monkeypatch):
    values = np.arange(4 * 5 * 6, dtype=np.float32).reshape(4, 5, 6)
    digest = step_cache.array_digest(values)
    assert step_cache.array_digest(values.copy()) == digest
    last = values.copy()
    last[-1, -1, -1] = np.nextafter(last[-1, -1, -1], np.float32(np.inf))
    assert step_cache.array_digest(last) != digest
    assert step_cache.array_digest(values.reshape(5, 4, 6).copy()) != digest
    assert step_cache.array_digest(values.astype(np.float64)) != digest
    monkeypatch.setattr(step_cache, "CHUNK_BYTES", 64)  # the threaded path: chunk digests
    chunked = step_cache.array_digest(values.copy())
    assert chunked != digest and step_cache.array_digest(values.copy()) == chunked
    assert step_cache.array_digest(last.copy()) != chunked
