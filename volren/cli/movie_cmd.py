"""`volren movie`: a scene rendered along a camera path (an orbit by default) into MP4 or GIF.

It takes every flag of `volren render` (the same scene, renderer, quality and camera: frame i
of the default orbit is `volren render --azimuth A + 360 i / N`); a scene file's "movie" object
adds keyframed cameras and TFs (`volren.model.animation`). --frames, --fps and --orbit override it.
At a quality level, a frame whose TF is of another class (smooth, sharp) than the first gets the
level's settings for its class, as `volren render` draws that TF.
A time series INPUT (a .pvd, or a folder of volume files) runs through its steps instead: one
frame a step at 10 a second, the camera still (--orbit turns it meanwhile).
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from typing import TYPE_CHECKING

from volren.cli.render_cmd import (
    add_scene_arguments,
    build_scene,
    check_outputs,
    check_scene_input,
    explained,
    finite_float,
    quality_asked,
    settings_level,
)
from volren.cli.time_steps import input_series
from volren.errors import VolrenError
from volren.model.animation import MAX_FPS, MAX_FRAMES, MIN_FPS, Animation, check_fps, check_frames
from volren.model.scene import Scene

if TYPE_CHECKING:
    from volren.bricked.source import BrickSource
    from volren.draw import DrawInput


def _frames(text: str) -> int:
    try:
        return check_frames(int(text), "--frames")
    except (ValueError, VolrenError):
        raise argparse.ArgumentTypeError(
            f"expected a whole number from 1 to {MAX_FRAMES:,}, got {text!r}"
        ) from None


def _fps(text: str) -> float:
    try:
        return check_fps(finite_float(text), "--fps")
    except (argparse.ArgumentTypeError, VolrenError):
        raise argparse.ArgumentTypeError(
            f"expected a number from {MIN_FPS:g} to {MAX_FPS:g}, got {text!r}"
        ) from None


def add_parser(sub) -> None:
    p = sub.add_parser("movie", help="render an orbit (or a scene's keyframes) offscreen to MP4 or GIF")
    p.add_argument("-o", "--output", help="movie file to write: .mp4 (H.264) or .gif")
    add_scene_arguments(p)
    p.add_argument(
        "--frames", type=_frames, help="number of frames (default 120, or the scene's movie.frames)"
    )
    p.add_argument("--fps", type=_fps, help="frames per second (default 30, or the scene's movie.fps)")
    p.add_argument("--orbit", type=finite_float, metavar="DEGREES",
                   help="turn the camera this far about the view-up axis (default 360; a scene's camera keyframes "
                        "replace the orbit)")  # fmt: skip
    p.add_argument("--lossless", action="store_true",
                   help="MP4 as lossless RGB H.264: decodes to exactly the frames `volren render` writes "
                        "(larger; not every player takes it)")  # fmt: skip
    p.add_argument("--force", action="store_true", help="write -o even over an input file")
    p.set_defaults(run=run)


#: A time series' movie: one frame a step, this many steps a second, the camera still.
SERIES_FPS = 10.0


def animation_of(args: argparse.Namespace, scene_movie: object, steps: int | None = None) -> Animation:
    """The scene file's movie (if any) with --frames, --fps and --orbit applied on top; for a
    time series of `steps` steps, one frame a step at SERIES_FPS with the camera still, unless
    those flags say otherwise."""
    if scene_movie is not None:
        animation = Animation.from_dict(scene_movie)  # type: ignore[arg-type]
    elif steps is not None:
        animation = Animation(frames=steps, fps=SERIES_FPS, orbit_degrees=0.0)
    else:
        animation = Animation()
    given = {key: value for key, value in (("frames", args.frames), ("fps", args.fps), ("orbit_degrees", args.orbit))
             if value is not None}  # fmt: skip
    if args.orbit is not None and animation.camera_keys:
        raise VolrenError(
            f"{args.scene}: --orbit turns the camera, but the scene's movie has camera keyframes"
        )
    return replace(animation, **given)


def run(args: argparse.Namespace) -> int:
    from volren.cli.progress import frame_bar
    from volren.io.movie_io import check_movie_fps, check_movie_path
    from volren.movie import render_movie

    if not args.output:
        raise VolrenError("give -o OUT.mp4 or -o OUT.gif")
    check_movie_path(args.output, "-o")
    if args.lossless and not args.output.lower().endswith(".mp4"):
        raise VolrenError(
            f"{args.output}: --lossless applies to MP4 movies only (a GIF has 256 colours a frame)"
        )
    inputs = [("input volume", args.input), ("--tf file", args.tf), ("--scene file", args.scene),
              ("--labels file", args.labels), ("--label-info file", args.label_info),
              *(("--channel-tf file", path) for _, path in args.channel_tf)]  # fmt: skip
    check_outputs((("-o", args.output),), inputs, args.force)
    series = input_series(args)
    if series is not None and args.time_step is not None:
        raise VolrenError(
            f"--time-step picks one step; a movie of {args.input} runs through all {len(series)}"
        )
    scene, why, source = build_scene(args)
    check_outputs((("-o", args.output),), [*inputs, ("scene's volume", scene.volume_path)], args.force)
    check_scene_input(args, scene)
    try:
        animation = animation_of(args, scene.extra.get("movie"), len(series) if series is not None else None)
    except VolrenError as exc:
        raise VolrenError(f"{args.scene}: {exc}" if args.scene else str(exc)) from None
    check_movie_fps(args.output, animation.fps)
    _check_labels(args, scene, animation, series is not None)
    _check_channels(args, scene, animation, series is not None)
    width, height = scene.size
    assert source is not None  # a scene without a volume was refused above
    scene, stream = _level_for_movie(args, scene, source)
    bounds = source.bounds if source.bricks else None
    try:
        with frame_bar(f"{scene.renderer} {width}x{height}", animation.frames) as progress:
            result = render_movie(scene, animation, args.output, lossless=args.lossless, progress=progress,
                                  steps=series.steps if series is not None else None, source=stream,
                                  bounds=bounds, level=settings_level(args, scene))  # fmt: skip
    except VolrenError as exc:
        raise explained(exc, args, scene, why) from None
    chosen_by = f" (auto: {why})" if why else ""
    seconds = result.total_ms / 1000
    print(f"{scene.renderer}{chosen_by}: {result.frames} frames of {width}x{height} at {result.fps:g} fps "
          f"({result.frames / result.fps:.1f} s of movie) in {seconds:.1f} s, median {result.median_frame_ms:.0f} ms "
          f"a frame -> {args.output}")  # fmt: skip
    return 0


def _check_labels(args: argparse.Namespace, scene: Scene, animation: Animation, series: bool) -> None:
    """A movie of a label volume draws that volume with its TF per label throughout: a time series
    (a volume read a step, without labels) and TF keyframes (one TF for all labels) are refused."""
    from volren.cli.label_flags import label_flag
    from volren.model.labels import LabelTransferFunction

    if not isinstance(scene.transfer_function, LabelTransferFunction):
        return
    what = label_flag(args) or f"{args.scene}: labels"
    if series:
        raise VolrenError(
            f"{what}: a label volume lies on one volume's grid; a time series' movie reads a volume a step"
        )
    if animation.tf_keys:
        raise VolrenError(f"{what}: the scene's movie has TF keyframes, which do not apply to a TF per label")


def _check_channels(args: argparse.Namespace, scene: Scene, animation: Animation, series: bool) -> None:
    """A movie of a multi-channel volume draws it with its TF per channel throughout: a time series
    (read a step at a time, one field each) and TF keyframes (one TF) are refused."""
    from volren.cli.channel_flags import channel_flag
    from volren.model.channels import ChannelTransferFunction

    if not isinstance(scene.transfer_function, ChannelTransferFunction):
        return
    what = channel_flag(args) or f"{args.scene}: channels"
    if series:
        raise VolrenError(f"{what}: a time series' movie reads a volume a step, one field each; channels are "
                          "drawn from one volume")  # fmt: skip
    if animation.tf_keys:
        raise VolrenError(
            f"{what}: the scene's movie has TF keyframes, which do not apply to a TF per channel"
        )


def _level_for_movie(
    args: argparse.Namespace, scene: Scene, source: DrawInput
) -> tuple[Scene, BrickSource | None]:
    """An OME-Zarr INPUT: the level its first frame needs for every frame, read whole or (larger
    than --memory) streamed brick by brick; (scene, the streamed source or None)."""
    if not source.bricks:
        return scene, None
    width, height = scene.size
    frame = source.frame(scene.renderer, scene.resolved_camera(source.bounds), width, height,
                         quality_asked(args, scene))  # fmt: skip
    if frame.volume is None:
        return scene, frame.source
    return scene.with_volume(frame.volume), None
