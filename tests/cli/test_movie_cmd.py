"""`volren movie`: decoded movies hold the frames `volren render` writes for the same cameras."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from volren import quality
from volren.cli.main import main
from volren.errors import VolrenError
from volren.io import load_volume
from volren.model.scene_class import SceneClass
from volren.model.settings import RenderSettings
from volren.model.tf_blend import blend_transfer_functions
from volren.model.transfer_function import TransferFunction1D
from volren.samples import sample_paths

imageio = pytest.importorskip("imageio.v2", reason="volren[movie] is part of the test set-up")
pytestmark = pytest.mark.usefixtures("opengl")
RENDERER = "vtk"  # quick at small sizes, and any renderer makes the same frames through the same code


@pytest.fixture(scope="module")
def ml_sample():
    return sample_paths("marschner_lobb")


def decoded(path: Path) -> list[np.ndarray]:
    return [np.asarray(frame)[..., :3] for frame in imageio.mimread(path, memtest=False)]


def rendered(tmp_path: Path, *args: str) -> np.ndarray:
    png = tmp_path / "frame.png"
    assert main(["render", *args, "-o", str(png), "--force"]) == 0
    return np.asarray(Image.open(png).convert("RGB"))


def keyed_tfs(ml_sample) -> tuple[TransferFunction1D, TransferFunction1D]:
    """The sample's smooth TF, and the same with thrice the opacity: a sharp one."""
    tf = TransferFunction1D.from_dict(json.loads(Path(ml_sample[1]).read_text()))
    bright = tf.copy()
    bright.set_opacity_points(np.clip(tf.opacity_points * [1, 3], 0, 1))
    return tf, bright


@pytest.mark.vtk
def test_lossless_mp4_holds_exactly_the_rendered_orbit(tmp_path, capsys, ml_sample):
    volume, tf = map(str, ml_sample)
    movie = tmp_path / "orbit.mp4"
    flags = [volume, "--tf", tf, "--renderer", RENDERER, "--size", "40x30", "--elevation", "20"]
    assert main(["movie", *flags, "-o", str(movie), "--frames", "3", "--lossless"]) == 0
    line = capsys.readouterr().out.strip()
    assert line.startswith(f"{RENDERER}: 3 frames of 40x30 at 30 fps") and line.endswith(f"-> {movie}")
    frames = decoded(movie)
    assert len(frames) == 3
    for index, azimuth in enumerate(
        (0, 120, 240)
    ):  # a whole turn loops: the last frame is not the first again
        assert np.array_equal(frames[index], rendered(tmp_path, *flags, "--azimuth", str(azimuth))), index
    assert not frames[0].tobytes() == frames[1].tobytes()


@pytest.mark.vtk
def test_default_mp4_and_gif_decode_to_the_frames_within_their_codecs_loss(tmp_path, ml_sample):
    volume, tf = map(str, ml_sample)
    flags = [volume, "--tf", tf, "--renderer", RENDERER, "--size", "41x31", "--orbit", "90"]
    first = rendered(tmp_path, *flags[:-2]).astype(float)
    last = rendered(tmp_path, *flags[:-2], "--azimuth", "90").astype(float)
    for name, mean_error in (("movie.mp4", 3.0), ("movie.gif", 6.0)):
        assert main(["movie", *flags, "-o", str(tmp_path / name), "--frames", "4", "--fps", "10"]) == 0
        frames = decoded(tmp_path / name)
        assert len(frames) == 4, name
        # yuv420p needs even sides: the odd side is padded by its last row and column, never scaled
        height, width = frames[0].shape[:2]
        assert (width, height) == ((42, 32) if name.endswith(".mp4") else (41, 31))
        assert np.abs(frames[0][:31, :41] - first).mean() < mean_error, name
        assert np.abs(frames[-1][:31, :41] - last).mean() < mean_error, name  # a part turn ends on its angle
        assert np.abs(frames[-1][:31, :41] - first).mean() > 2 * mean_error, name


@pytest.mark.vtk
def test_scene_keyframes_move_the_camera_and_blend_the_tf(tmp_path, ml_sample):
    volume, tf_path = ml_sample
    tf, bright = keyed_tfs(ml_sample)
    (tmp_path / "bright.json").write_text(json.dumps(bright.to_dict()))
    scene = {
        "version": 1,
        "volume": {"path": str(volume)},
        "transfer_function": tf.to_dict(),
        "renderer": RENDERER,
        "quality": "default",
        "size": [32, 32],
        "movie": {
            "frames": 3,
            "fps": 5,
            "keyframes": [
                {"time": 0, "camera": {"azimuth": 0, "elevation": 10}},
                {"time": 1, "camera": {"azimuth": 60, "elevation": 30}, "transfer_function": "bright.json"},
                {"time": 0, "transfer_function": tf.to_dict()},
            ],
        },
    }
    (tmp_path / "scene.json").write_text(json.dumps(scene))
    movie = tmp_path / "keys.mp4"
    assert main(["movie", "--scene", str(tmp_path / "scene.json"), "-o", str(movie), "--lossless"]) == 0
    frames = decoded(movie)
    assert len(frames) == 3
    middle_tf = tmp_path / "middle.json"
    middle_tf.write_text(json.dumps(blend_transfer_functions(tf, bright, 0.5).to_dict()))
    # each frame is drawn at the level's settings for its own TF's class, as `volren render` draws
    # that TF: the first two are smooth, the bright one alone is sharp, whose settings differ
    kinds = [
        SceneClass.of(load_volume(volume), t) for t in (tf, blend_transfer_functions(tf, bright, 0.5), bright)
    ]
    assert [str(k) for k in kinds] == ["uniform/smooth", "uniform/smooth", "uniform/sharp"]
    smooth, sharp = (quality.table().measurement(RENDERER, kind, "default").level for kind in kinds[1:])
    assert (smooth.step, smooth.options) != (sharp.step, sharp.options)
    flags = [str(volume), "--renderer", RENDERER, "--size", "32", "--quality", "default"]
    expected = [
        rendered(tmp_path, *flags, "--tf", str(tf_path), "--azimuth", "0", "--elevation", "10"),
        rendered(tmp_path, *flags, "--tf", str(middle_tf), "--azimuth", "30", "--elevation", "20"),
        rendered(
            tmp_path, *flags, "--tf", str(tmp_path / "bright.json"), "--azimuth", "60", "--elevation", "30"
        ),
    ]
    for index, image in enumerate(expected):
        assert np.array_equal(frames[index], image), index


@pytest.mark.parametrize("explicit", [False, True])
@pytest.mark.vtk
def test_a_movie_at_a_level_draws_each_frame_at_its_tf_class_settings(
    tmp_path, ml_sample, monkeypatch, explicit
):
    """The sharp part of a smooth-to-sharp movie gets the sharp level's settings, set once where the
    class changes; settings that are not a level's (the user's) stay for every frame."""
    from volren.model.animation import Animation, TFKey
    from volren.model.scene import Scene
    from volren.movie import render_movie
    from volren.renderers.base import RendererBase

    volume = load_volume(ml_sample[0])
    smooth_tf, sharp_tf = keyed_tfs(ml_sample)
    smooth, sharp = (quality.at_level(RENDERER, SceneClass.of(volume, t), "default", RenderSettings())
                     for t in (smooth_tf, sharp_tf))  # fmt: skip
    assert smooth != sharp and str(SceneClass.of(volume, sharp_tf)) == "uniform/sharp"
    start = smooth.with_(step=0.3) if explicit else smooth
    drawn: list = []
    set_settings = RendererBase.set_settings
    monkeypatch.setattr(
        RendererBase, "set_settings", lambda self, s: (drawn.append(s), set_settings(self, s))
    )
    scene = Scene(
        str(ml_sample[0]), smooth_tf, volume=volume, renderer=RENDERER, settings=start, size=(16, 16)
    )
    animation = Animation(frames=5, tf_keys=(TFKey(0.0, smooth_tf), TFKey(1.0, sharp_tf)))
    render_movie(scene, animation, tmp_path / "m.gif", level="default")
    assert drawn == (
        [start] if explicit else [smooth, sharp]
    )  # prepared with the scene's; then the sharp frame's


@pytest.mark.parametrize(
    "args, message",
    [
        (["-o", "{tmp}/m.avi"], "a movie is written as .mp4 or .gif"),
        (["-o", "{tmp}/m.gif", "--lossless"], "--lossless applies to MP4 movies only"),
        (["-o", "{tmp}/no/such/m.mp4"], "does not exist"),
        ([], "give -o OUT.mp4"),
        (["-o", "{volume}"], "a movie is written as"),
        (["-o", "{tmp}/m.mp4", "--scene", "{scene}"], "movie: keyframe 0: 'time' must be a number in [0, 1]"),
        (["-o", "{tmp}/m.mp4", "--scene", "{scene}", "--orbit", "90"], "movie: keyframe 0"),
    ],
)
def test_bad_movie_requests_are_one_line_errors(tmp_path, capsys, ml_sample, args, message):
    volume, tf = map(str, ml_sample)
    scene = tmp_path / "bad_scene.json"
    scene.write_text(
        json.dumps(
            {
                "version": 1,
                "volume": {"path": volume},
                "transfer_function": json.loads(Path(tf).read_text()),
                "movie": {"keyframes": [{"time": 3, "camera": {}}]},
            }
        )
    )
    fill = {"tmp": str(tmp_path), "volume": volume, "scene": str(scene)}
    argv = ["movie", *([] if "--scene" in args else [volume]), *(a.format(**fill) for a in args)]
    assert main(argv) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("volren: error: ") and message in err[0], err
    if "--scene" in args:
        assert str(scene) in err[0]
    assert not list(tmp_path.glob("*.mp4")) and not list(tmp_path.glob(".*partial*"))


def test_orbit_flag_and_camera_keyframes_conflict(tmp_path, capsys, ml_sample):
    volume, tf = map(str, ml_sample)
    scene = tmp_path / "scene.json"
    scene.write_text(
        json.dumps(
            {
                "version": 1,
                "volume": {"path": volume},
                "transfer_function": json.loads(Path(tf).read_text()),
                "movie": {"keyframes": [{"time": 0, "camera": {}}]},
            }
        )
    )
    assert main(["movie", "--scene", str(scene), "-o", str(tmp_path / "m.mp4"), "--orbit", "90"]) == 1
    assert "--orbit turns the camera, but the scene's movie has camera keyframes" in capsys.readouterr().err


@pytest.mark.vtk
def test_a_failed_movie_leaves_no_file_and_keeps_an_older_one(tmp_path, ml_sample):
    from volren.io import load_volume
    from volren.model.animation import Animation
    from volren.model.scene import Scene
    from volren.movie import render_movie

    volume = load_volume(ml_sample[0])
    scene = Scene(
        str(ml_sample[0]), TransferFunction1D.ramp(0, 1), volume=volume, renderer=RENDERER, size=(16, 16)
    )
    target = tmp_path / "kept.gif"
    target.write_bytes(b"an older movie")

    def stop_after_two(fraction: float) -> None:
        if fraction >= 2 / 5:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        render_movie(scene, Animation(frames=5), target, progress=stop_after_two)
    assert target.read_bytes() == b"an older movie"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kept.gif"]
    result = render_movie(replace(scene, renderer="auto"), Animation(frames=2, fps=4), target)
    assert (result.frames, result.width, result.height, result.fps) == (2, 16, 16, 4.0)
    assert len(decoded(target)) == 2


@pytest.mark.vtk
def test_a_time_series_renders_a_step_and_moves_through_all_steps(tmp_path, capsys):
    """Issue 23: time series on the command line: --time-step N renders that step; a movie of a
    series runs through its steps, one frame each, camera still."""
    from tests.app.test_time_series import write_pvd, write_steps

    steps = write_steps(tmp_path, 3)
    pvd = write_pvd(tmp_path / "run.pvd", [(k, p.name) for k, p in enumerate(steps)])
    tf = tmp_path / "tf.json"
    tf.write_text(json.dumps(TransferFunction1D.ramp(0, 3, 0.8).to_dict()))
    flags = ["--tf", str(tf), "--renderer", RENDERER, "--size", "24"]
    np.testing.assert_array_equal(rendered(tmp_path, str(pvd), *flags, "--time-step", "2"),
                                  rendered(tmp_path, str(steps[2]), *flags))  # fmt: skip
    movie = tmp_path / "series.mp4"
    assert main(["movie", str(pvd), *flags, "-o", str(movie), "--lossless"]) == 0
    assert "3 frames of 24x24 at 10 fps" in capsys.readouterr().out
    frames = decoded(movie)
    assert len(frames) == 3
    for index, step in enumerate(steps):
        np.testing.assert_array_equal(
            frames[index], rendered(tmp_path, str(step), *flags), err_msg=str(index)
        )
    assert main(["movie", str(pvd), *flags, "-o", str(movie), "--time-step", "1"]) == 1
    assert "--time-step picks one step" in capsys.readouterr().err
    assert main(["render", str(pvd), *flags, "-o", str(tmp_path / "x.png"), "--time-step", "3"]) == 1
    assert "--time-step 3: " in capsys.readouterr().err


def test_a_movie_of_an_ome_zarr_level_larger_than_memory_streams_every_frame(tmp_path, capsys):
    """Issue 24: each frame streamed brick by brick, the same pixels as `volren render` draws."""
    pytest.importorskip("zarr", reason="volren[zarr] is part of the test set-up")
    from volren.io.ome_zarr_io import save_ome_zarr
    from volren.model.volume import UniformVolume

    z, y, x = np.meshgrid(np.arange(18), np.arange(20), np.arange(22), indexing="ij")
    values = (2000 + 1500 * np.sin(0.4 * x) * np.cos(0.3 * y) + 50 * z).astype(np.uint16)
    path = tmp_path / "field.zarr"
    save_ome_zarr(UniformVolume(values, name="field"), path, chunk=8, levels=2)
    flags = [str(path), "--renderer", "reference", "--size", "24x20", "--level", "0", "--memory", "4KB"]
    movie = tmp_path / "field.mp4"
    assert main(["movie", *flags, "-o", str(movie), "--frames", "2", "--lossless"]) == 0
    capsys.readouterr()
    frames = decoded(movie)
    assert len(frames) == 2
    for index, azimuth in enumerate((0, 180)):
        assert np.array_equal(frames[index], rendered(tmp_path, *flags, "--azimuth", str(azimuth))), index
    assert "streamed" in capsys.readouterr().out


@pytest.mark.parametrize("fps, name", [("1e-300", "m.mp4"), ("1e-6", "m.mp4"), ("0.001", "m.gif")])
def test_an_fps_no_movie_can_have_is_refused_naming_fps(tmp_path, capsys, ml_sample, fps, name):
    """ffmpeg wrote a 0-byte MP4 at 1e-300 fps and one without video at 1e-6, and the command
    said it was done; a GIF frame longer than 655 s was a traceback from Pillow."""
    volume, tf = map(str, ml_sample)
    argv = ["movie", volume, "--tf", tf, "--renderer", RENDERER, "--size", "8", "--frames", "2", "--fps", fps]
    with pytest.raises(SystemExit) as exc:
        main([*argv, "-o", str(tmp_path / name)])
    err = capsys.readouterr().err.strip().splitlines()
    assert exc.value.code == 2 and err[-1] == (f"volren movie: error: argument --fps: expected a number from 0.01 to "
                                               f"240, got '{fps}' (see volren movie --help)")  # fmt: skip
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("where", ["folder", "unwritable"])
def test_a_movie_output_that_cannot_be_written_is_one_line_before_rendering(
    tmp_path, capsys, ml_sample, where
):
    import os

    volume, tf = map(str, ml_sample)
    if where == "folder":
        (tmp_path / "m.mp4").mkdir()
        target, message = tmp_path / "m.mp4", f"{tmp_path / 'm.mp4'}: -o must be a file, not a folder"
    elif os.geteuid() == 0:  # root writes anywhere but in /proc
        target, message = (
            Path("/proc/volren-test.mp4"),
            "/proc/volren-test.mp4: cannot write in the folder /proc",
        )
    else:
        (tmp_path / "locked").mkdir(mode=0o500)
        target, message = tmp_path / "locked" / "m.mp4", "m.mp4: cannot write in the folder"
    argv = [
        "movie",
        volume,
        "--tf",
        tf,
        "--renderer",
        RENDERER,
        "--size",
        "8",
        "--frames",
        "2",
        "-o",
        str(target),
    ]
    assert main(argv) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("volren: error: ") and message in err[0], err
    assert not target.is_file() and not list(tmp_path.rglob("*partial*"))


def test_a_movie_the_encoder_did_not_write_is_an_error_and_leaves_no_file(tmp_path, monkeypatch):
    """ffmpeg can fail without a word to the writer: the movie's frames are counted in the file."""
    from volren.io.movie_io import MovieWriter, movie_writer

    class SilentlyBroken:
        def append_data(self, frame: np.ndarray) -> None:
            pass

        def close(self) -> None:
            pass

    monkeypatch.setattr(MovieWriter, "_open", lambda self, imageio, tmp: SilentlyBroken())
    for name in ("m.mp4", "m.gif"):
        with pytest.raises(VolrenError, match=rf"^{tmp_path / name}: cannot finish the movie: the encoder wrote 0 "
                                              rf"of its 2 frames$"), movie_writer(tmp_path / name, 10) as writer:  # fmt: skip
            for _ in range(2):
                writer.append(np.zeros((8, 8, 3), np.uint8))
    assert list(tmp_path.iterdir()) == []


def test_the_movie_writer_refuses_an_fps_it_cannot_write(tmp_path):
    """At 0.001 fps a GIF frame lasts 1000 s, over GIF's 655: Pillow failed with a traceback."""
    from volren.io.movie_io import movie_writer

    with pytest.raises(VolrenError, match=r"^fps must be a number from 0\.01 to 240, got 0\.001$"):
        with movie_writer(tmp_path / "m.gif", 0.001) as writer:
            writer.append(np.zeros((8, 8, 3), np.uint8))
    assert list(tmp_path.iterdir()) == []


def test_a_gif_faster_than_it_can_play_is_refused_before_the_first_frame(tmp_path, capsys, ml_sample):
    """A GIF's frames last whole hundredths of a second: at 240 fps Pillow wrote delays of 0, which
    browsers play at 10 fps, and the command said 240."""
    from volren.io.movie_io import GIF_MAX_FPS, movie_writer

    volume, tf = map(str, ml_sample)
    argv = ["movie", volume, "--tf", tf, "--renderer", RENDERER, "--size", "8", "--frames", "2"]
    assert main([*argv, "--fps", "240", "-o", str(tmp_path / "m.gif")]) == 1
    assert capsys.readouterr().err.splitlines() == [
        f"volren: error: {tmp_path / 'm.gif'}: a GIF plays at most 50 frames a second (its frames last whole "
        "hundredths of a second, 2 at least in browsers); for 240 fps write an MP4"
    ]
    assert list(tmp_path.iterdir()) == []
    with movie_writer(tmp_path / "m.gif", GIF_MAX_FPS) as writer:
        for value in (0, 255):
            writer.append(np.full((8, 8, 3), value, np.uint8))
    with Image.open(tmp_path / "m.gif") as gif:
        assert gif.n_frames == 2 and gif.info["duration"] == 1000 / GIF_MAX_FPS
