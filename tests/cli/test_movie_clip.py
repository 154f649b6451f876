"""Clip keyframes: a movie moves its planes between keys, each frame as `volren render --clip`
draws that plane, and `auto` picks a renderer that clips when only the keyframes clip."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from volren.cli.main import main
from volren.errors import VolrenError
from volren.model.animation import Animation
from volren.model.clip_region import ClipPlane, ClipRegion, blend_clip_regions
from volren.renderers.registry import registry
from volren.samples import sample_paths

imageio = pytest.importorskip("imageio.v2", reason="volren[movie] is part of the test set-up")


def _scene(tmp_path: Path, renderer: str, keys: list[dict]) -> Path:
    volume, tf = sample_paths("marschner_lobb")
    scene = {
        "version": 1,
        "volume": {"path": str(volume)},
        "transfer_function": json.loads(Path(tf).read_text()),
        "renderer": renderer,
        "size": [32, 32],
        "camera": {"azimuth": 30, "elevation": 20},
        "movie": {"frames": 3, "fps": 5, "orbit": 0, "keyframes": keys},
    }
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene))
    return path


def _plane(x: float) -> dict:
    return {"planes": [{"origin": [x, 0.0, 0.0], "normal": [-1.0, 0.0, 0.0]}]}


def test_clip_keyframes_move_the_plane_and_each_frame_is_the_clipped_render(tmp_path):
    scene = _scene(tmp_path, "raycast", [{"time": 0, "clip": _plane(0.6)}, {"time": 1, "clip": _plane(-0.4)}])
    movie = tmp_path / "cut.mp4"
    assert main(["movie", "--scene", str(scene), "-o", str(movie), "--lossless"]) == 0
    frames = [np.asarray(f)[..., :3] for f in imageio.mimread(movie, memtest=False)]
    assert len(frames) == 3
    for frame, x in zip(frames, (0.6, 0.1, -0.4), strict=True):
        png = tmp_path / "frame.png"
        assert (
            main(["render", "--scene", str(scene), f"--clip={x},0,0,-1,0,0", "-o", str(png), "--force"]) == 0
        )
        assert np.array_equal(frame, np.asarray(Image.open(png).convert("RGB"))), x
    assert not np.array_equal(frames[0], frames[2])


def test_auto_picks_a_renderer_that_clips_when_only_the_keyframes_clip(tmp_path, capsys):
    scene = _scene(tmp_path, "auto", [{"time": 1, "clip": _plane(0.0)}])
    assert main(["movie", "--scene", str(scene), "-o", str(tmp_path / "m.gif")]) == 0
    name = capsys.readouterr().out.split(":")[0].split()[0]
    assert registry.capabilities(name).kinds["uniform"].clip_region, name


def test_clip_keyframes_blend_points_normals_and_boxes():
    a = ClipRegion((ClipPlane((0, 0, 0), (1, 0, 0)),), (0, 2, 0, 2, 0, 2))
    b = ClipRegion((ClipPlane((2, 0, 0), (0, 1, 0), invert=True),), (1, 3, 0, 2, 0, 4))
    mid = blend_clip_regions(a, b, 0.5)
    assert mid.planes[0].origin == (1.0, 0.0, 0.0)
    assert np.allclose(
        np.asarray(mid.planes[0].normal) / np.linalg.norm(mid.planes[0].normal), [0.5**0.5] * 2 + [0]
    )
    assert mid.box == (0.5, 2.5, 0.0, 2.0, 0.0, 3.0)
    assert (
        blend_clip_regions(a, b, 0.25).planes[0].invert is False
        and blend_clip_regions(a, b, 0.75).planes[0].invert
    )
    assert blend_clip_regions(a, b, 0.0) is a and blend_clip_regions(a, b, 1.0) is b


def test_clip_keyframes_with_different_plane_counts_are_refused_in_one_line():
    keys = [{"time": 0, "clip": _plane(0.0)}, {"time": 1, "clip": {"planes": []}}]
    with pytest.raises(VolrenError, match="movie: clip keyframes must all hold the same number of planes"):
        Animation.from_dict({"frames": 2, "keyframes": keys})


def test_clip_cap_draws_the_cut_faces_and_needs_a_cut(tmp_path, capsys):
    volume, tf = sample_paths("marschner_lobb")
    plain, capped = tmp_path / "plain.npy", tmp_path / "capped.npy"
    flags = [
        str(volume),
        "--tf",
        str(tf),
        "--size",
        "24",
        "--renderer",
        "raycast",
        "--clip=0,0,0,-1,0,0",
        "--azimuth",
        "60",
    ]
    assert main(["render", *flags, "--save-array", str(plain)]) == 0
    assert main(["render", *flags, "--clip-cap", "--save-array", str(capped)]) == 0
    assert (np.load(capped)[..., 3] == 1.0).sum() > (np.load(plain)[..., 3] == 1.0).sum() + 20
    capsys.readouterr()
    assert main(["render", str(volume), "--clip-cap", "-o", str(tmp_path / "x.png")]) == 1
    assert (
        capsys.readouterr().err.strip()
        == "volren: error: --clip-cap: give --clip or --crop (there is nothing cut to cap)"
    )
