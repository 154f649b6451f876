"""`volren render`: one offscreen frame to a PNG (and optionally the float RGBA array).

Flags follow DESIGN.md. With ``--scene SCENE.json`` the scene supplies the volume, TF, camera,
settings, renderer and size; flags given explicitly override it.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from contextlib import AbstractContextManager
from dataclasses import replace
from pathlib import Path
from typing import Any

from volren.cli.channel_flags import add_channel_arguments, load_channel_input, pick_of, with_channel_flags
from volren.cli.cluster_frame import add_cluster_arguments, check_cluster_flag, wants_cluster
from volren.cli.label_flags import add_label_arguments, with_label_flags
from volren.cli.raw_flags import add_raw_arguments, check_raw_flags, raw_load_arguments
from volren.cli.stage_clock import StageClock
from volren.cli.time_steps import step_path
from volren.draw import Drawing, DrawInput, VolumeInput, Watch
from volren.errors import VolrenError
from volren.model.camera import check_zoom
from volren.model.clip_region import MAX_PLANES, Box, ClipPlane, ClipRegion, check_box
from volren.model.scene import OrbitView, Scene
from volren.model.settings import MAX_SAMPLES_PER_RAY, MAX_STEP, BlendMode
from volren.quality import DEFAULT_LEVEL, LEVELS
from volren.renderers.base import ProgressCallback

#: How messages mark a renderer that the user did not name.
CHOSEN_BY_AUTO = "(chosen by --renderer auto)"


def finite_float(text: str) -> float:
    """An argparse type: a finite number (NaN or Inf is a usage error naming the flag, where the
    camera would otherwise fail later with a message that names no flag)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def positive_float(text: str) -> float:
    """An argparse type: a finite number above 0 (for --zoom and --step)."""
    value = finite_float(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a number above 0, got {text!r}")
    return value


def step_length(text: str) -> float:
    """An argparse type for --step: above 0 and at most MAX_STEP voxel lengths."""
    value = positive_float(text)
    if value > MAX_STEP:
        raise argparse.ArgumentTypeError(f"expected at most {MAX_STEP:g} (voxel lengths), got {text!r}")
    return value


def clip_plane(text: str) -> ClipPlane:
    """An argparse type for --clip: OX,OY,OZ,NX,NY,NZ, a point of the plane and its normal."""
    try:
        return ClipPlane.parse(text)
    except VolrenError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def crop_box(text: str) -> Box:
    """An argparse type for --crop: XMIN,XMAX,YMIN,YMAX,ZMIN,ZMAX in world units."""
    try:
        return check_box(text.split(","))
    except VolrenError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def image_size(text: str) -> tuple[int, int]:
    """An argparse type: W or WxH, each side in 1..MAX_IMAGE_SIDE."""
    from volren.api import parse_size
    from volren.renderers.base import MAX_IMAGE_SIDE

    try:
        width, height = parse_size(text)
    except VolrenError:
        raise argparse.ArgumentTypeError(
            f"expected W or WxH in pixels (e.g. 512 or 640x480), got {text!r}"
        ) from None
    if max(width, height) > MAX_IMAGE_SIDE:
        raise argparse.ArgumentTypeError(f"each side may be at most {MAX_IMAGE_SIDE} pixels, got {text!r}")
    return width, height


def memory_size(text: str) -> int:
    """An argparse type for --memory: its bytes ("2GB", "512MB", ...). Read only once the image
    was open, a size that is none was an error naming no flag."""
    from volren.io.ome_zarr_io import parse_memory

    try:
        return parse_memory(text)
    except VolrenError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def add_parser(sub) -> None:
    p = sub.add_parser("render", help="render a volume offscreen to a PNG")
    p.add_argument("-o", "--output", help="PNG file to write")
    add_scene_arguments(p)
    p.add_argument("--save-array", metavar="OUT.npy", help="also save float32 (H, W, 4) RGBA, row 0 on top")
    p.add_argument("--transparent", action="store_true", help="PNG with alpha instead of over black")
    p.add_argument("--force", action="store_true", help="write -o / --save-array even over an input file")
    p.add_argument(
        "--timings",
        action="store_true",
        help="print the wall time of each stage (start-up, load, set-up, frame, write) on stderr",
    )
    add_cluster_arguments(p)
    p.set_defaults(run=run)


def add_scene_arguments(p: argparse.ArgumentParser) -> None:
    """What to render and how: the flags `volren render` and `volren movie` share (`build_scene`)."""
    p.add_argument("input", nargs="?", help="volume file or DICOM folder (optional with --scene)")
    p.add_argument("--scene", help="scene JSON with volume, TF, camera and settings")
    p.add_argument(
        "--renderer",
        help="renderer name (see `volren renderers`), or auto (the default: the fastest "
        "measured renderer that draws the scene at the quality asked for)",
    )
    p.add_argument(
        "--quality",
        choices=LEVELS,
        help="settings measured for this level (volren renderers lists them; "
        "default: default, or the scene file's settings as they are); explicit flags win",
    )
    p.add_argument("--tf", help="transfer function JSON (DESIGN.md format or a ParaView preset)")
    add_label_arguments(p)
    add_channel_arguments(p)
    p.add_argument("--time-step", type=int, metavar="N",
                   help="for a time series INPUT (a .pvd, or a folder of volume files): the step to render, from 0 "
                        "(default 0)")  # fmt: skip
    p.add_argument("--level", type=int, metavar="N",
                   help="for an OME-Zarr INPUT: the pyramid level to render, 0 the full resolution (default: with a "
                        "renderer that draws bricks, 0, or at --quality draft and interactive the coarsest whose "
                        "voxels look no larger than a pixel; with another, the finest that fits in --memory)")  # fmt: skip
    p.add_argument("--memory", type=memory_size, metavar="SIZE",
                   help="for an OME-Zarr INPUT: the most its data may take in memory, e.g. 2GB (default 8GB): a "
                        "level read whole counts with the renderer's float copies of it (a uint16 level drawn by the "
                        "slicer takes 16x its bytes), a larger one streams brick by brick within it (renderers that "
                        "draw bricks). The command's fixed overhead comes on top (interpreter, libraries, GL: about "
                        "370 MiB with the slicer): its peak is about that plus SIZE")  # fmt: skip
    p.add_argument(
        "--scalars",
        help="the array to render: NAME, or NAME:magnitude / NAME:x (y, z, 0, 1, ...) for a "
        "vector's length or one component (a vector shows its magnitude by default)",
    )
    p.add_argument("--size", type=image_size, help="image size W or WxH (default 512)")
    p.add_argument("--azimuth", type=finite_float, help="degrees, after the camera reset")
    p.add_argument("--elevation", type=finite_float, help="degrees, after the azimuth")
    p.add_argument("--zoom", type=positive_float, help="zoom factor, after the elevation")
    p.add_argument("--parallel", action="store_true", default=None, help="parallel projection")
    p.add_argument(
        "--step",
        type=step_length,
        help=f"sample distance in smallest voxel spacings / mean tet edges (at most {MAX_SAMPLES_PER_RAY:,} per ray)",
    )
    p.add_argument("--preintegration", action=argparse.BooleanOptionalAction, help="pre-integrated TF")
    p.add_argument("--shade", action=argparse.BooleanOptionalAction, help="Blinn-Phong shading")
    p.add_argument("--blend", choices=[m.value for m in BlendMode], help="blend mode (default composite)")
    p.add_argument("--clip", type=clip_plane, action="append", default=[], metavar="OX,OY,OZ,NX,NY,NZ",
                   help=f"keep the side of the plane through point O that normal N points to (world units; "
                        f"repeatable, at most {MAX_PLANES}; added to a scene's planes; --clip=-1,... when the first number "
                        f"is negative)")  # fmt: skip
    p.add_argument("--clip-cap", action="store_true", default=None,
                   help="draw the cut faces of --clip and --crop opaque, in the TF's colour there (lit with the "
                        "plane's normal when shading)")  # fmt: skip
    p.add_argument("--crop", type=crop_box, metavar="XMIN,XMAX,YMIN,YMAX,ZMIN,ZMAX",
                   help="keep the inside of this box (world units; replaces a scene's crop box; --crop=-1,... when the "
                        "first number is negative)")  # fmt: skip
    p.add_argument(
        "--option", action="append", default=[], metavar="KEY=VALUE", help="renderer-specific option"
    )
    add_raw_arguments(p)


def parse_options(items: list[str]) -> dict[str, Any]:
    """KEY=VALUE pairs; VALUE is read as JSON when it parses, else kept as text."""
    options = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise VolrenError(f"--option needs KEY=VALUE, got {item!r}")
        try:
            options[key] = json.loads(value)
        except json.JSONDecodeError:
            options[key] = value
    return options


def _ome_zarr_image(args: argparse.Namespace, path: str) -> DrawInput | None:
    """For an OME-Zarr INPUT, the opened image (the scene is set up on its coarsest level; the
    level drawn is decided once the renderer and camera are known: `ZarrInput.frame`); the flags
    refused for other inputs (None then: load INPUT as any volume)."""
    from volren.draw import is_ome_zarr_path, open_ome_zarr

    if not is_ome_zarr_path(path):
        flag = _zarr_flag(args)
        if flag:
            raise VolrenError(
                f"{flag} applies to an OME-Zarr INPUT (a .zarr folder or URL); {path} is not one"
            )
        return None
    if args.scalars is not None:
        raise VolrenError(f"{path}: an OME-Zarr image holds one field; --scalars does not apply")
    return open_ome_zarr(path, args.memory, args.level, "--memory")


def _zarr_flag(args: argparse.Namespace) -> str | None:
    """The first flag given that applies to an OME-Zarr INPUT only."""
    return "--level" if args.level is not None else "--memory" if args.memory is not None else None


def _check_zarr_flags(args: argparse.Namespace) -> None:
    """--level and --memory refused where no OME-Zarr INPUT is read (a scene's own volume is read
    whole, headerless raw data has no levels): silently ignored, they would change nothing."""
    flag = _zarr_flag(args)
    if flag and ((args.input is None and args.scene) or args.raw_shape):
        what = "headerless raw data" if args.raw_shape else "the scene's volume (give the image as INPUT)"
        raise VolrenError(f"{flag} applies to an OME-Zarr INPUT (a .zarr folder or URL), not to {what}")


def _load_input(args: argparse.Namespace, channels: Any = None) -> DrawInput:
    """INPUT (or the time step asked for) to draw from: an OME-Zarr image, or a volume read whole
    (with the channels --channels, else `channels`, picks)."""
    from volren import io

    kwargs: dict[str, Any] = {"scalars": args.scalars, **raw_load_arguments(args)}
    path = step_path(args)
    pick = pick_of(args, channels)
    if pick is not None:
        from volren.draw import is_ome_zarr_path

        flag = _zarr_flag(args)
        if flag and (args.raw_shape or not is_ome_zarr_path(path)):
            raise VolrenError(
                f"{flag} applies to an OME-Zarr INPUT (a .zarr folder or URL); {path} is not one"
            )
        return load_channel_input(args, path, pick)
    image = None if args.raw_shape else _ome_zarr_image(args, path)
    return image if image is not None else VolumeInput(io.load_volume(path, **kwargs))


def build_scene(args: argparse.Namespace) -> tuple[Scene, str | None, DrawInput | None]:
    """The scene to render: from --scene and/or INPUT, at the quality asked for, with explicit flags
    applied on top; why `auto` chose its renderer (None when a renderer was named); and what the
    frames are drawn from (None when the scene names no volume)."""
    from volren import io
    from volren.api import as_transfer_function
    from volren.io.tf_io import load_any_transfer_function

    check_raw_flags(args, "render")
    _check_zarr_flags(args)
    source: DrawInput | None = None
    if args.scene:
        scene = io.load_scene(args.scene, load_volume=args.input is None and args.channels is None)
        if args.input is not None:
            source = _load_input(args, scene.channels)
            scene = replace(scene, volume=source.stand_in(), volume_path=args.input)
        elif (
            args.channels is not None and scene.volume_path is not None
        ):  # the scene's volume, these channels
            source = load_channel_input(args, scene.volume_path, args.channels)
            scene = replace(scene, volume=source.stand_in())
        elif scene.volume is not None:
            source = VolumeInput(scene.volume)
    elif args.input is not None:
        source = _load_input(args)
        volume = source.stand_in()
        tf = load_any_transfer_function(args.tf) if args.tf else as_transfer_function(None, volume)
        scene = Scene(args.input, tf, volume=volume, scalars=args.scalars)
    else:
        raise VolrenError("give an INPUT volume or --scene SCENE.json")
    if args.tf and args.scene:
        scene = replace(
            scene,
            transfer_function=_over_labels(scene.transfer_function, load_any_transfer_function(args.tf)),
        )
    scene, source = with_channel_flags(args, scene, source, wants_cluster(args))
    scene, source = with_label_flags(args, scene, source, wants_cluster(args))
    if args.renderer is not None:
        if not args.renderer.strip():
            raise VolrenError("--renderer: give a renderer name (see `volren renderers`), got an empty one")
        scene = replace(scene, renderer=args.renderer)
    if args.size:
        scene = replace(scene, size=args.size)
    orbit_flags = {
        "azimuth": args.azimuth,
        "elevation": args.elevation,
        "zoom": args.zoom,
        "parallel": args.parallel,
    }
    if any(v is not None for v in orbit_flags.values()):
        base = scene.camera if isinstance(scene.camera, OrbitView) else OrbitView()
        if args.zoom is not None:
            check_zoom(args.zoom, bool(args.parallel or base.parallel), name="--zoom")
        scene = replace(
            scene, camera=replace(base, **{k: v for k, v in orbit_flags.items() if v is not None})
        )
    # shading and the blend mode decide what `auto` may pick; step, pre-integration and options win over the level's
    shown = {k: v for k, v in (("shade", args.shade), ("blend_mode", args.blend)) if v is not None}
    if args.clip or args.crop or args.clip_cap:  # clipping decides it too
        clip = scene.settings.clip
        if len(clip.planes) + len(args.clip) > MAX_PLANES:
            raise VolrenError(f"--clip: at most {MAX_PLANES} clip planes, the scene's included")
        shown["clip"] = ClipRegion(
            (*clip.planes, *args.clip), args.crop or clip.box, bool(args.clip_cap or clip.cap)
        )
        if args.clip_cap and shown["clip"].is_empty:
            raise VolrenError("--clip-cap: give --clip or --crop (there is nothing cut to cap)")
    if shown:
        scene = replace(scene, settings=scene.settings.with_(**shown))
    scene, why = _at_quality(args, scene, source)
    sampling: dict[str, Any] = {k: v for k, v in (("step", args.step), ("preintegration", args.preintegration))
                                if v is not None}  # fmt: skip
    if args.option:
        given = parse_options(args.option)
        _check_option_names(given, scene.renderer, why)
        sampling["options"] = {**scene.settings.options, **given}
    if sampling:
        scene = replace(scene, settings=scene.settings.with_(**sampling))
    return scene, why, source


def _over_labels(old: object, new: Any) -> Any:
    """--tf over a scene file's TF: over a TF per label, the new 1D TF is its base (the labels keep
    their styles); else the new TF."""
    from volren.model.labels import LabelTransferFunction
    from volren.model.transfer_function import TransferFunction1D

    if isinstance(old, LabelTransferFunction) and isinstance(new, TransferFunction1D):
        tf = old.copy()
        tf.set_base(new)
        return tf
    return new


def _check_option_names(options: dict[str, Any], renderer: str, why: str | None) -> None:
    """--option keys the renderer does not have, as a one-line error naming the flag (and saying
    that `auto` chose the renderer, when it did)."""
    from volren.renderers.registry import registry

    valid = registry.get(renderer).option_help
    unknown = [key for key in options if key not in valid]
    if unknown:
        key = unknown[0] if len(unknown[0]) <= 40 else unknown[0][:40] + "..."
        chosen = f"{CHOSEN_BY_AUTO} " if why else ""
        raise VolrenError(f"--option {key}: renderer {renderer} {chosen}has no such option; valid: "
                          f"{', '.join(sorted(valid)) or 'none'}")  # fmt: skip


def _at_quality(args: argparse.Namespace, scene: Scene, source: DrawInput | None) -> tuple[Scene, str | None]:
    """The scene's renderer resolved (`auto`) and its settings at the quality level asked for: the
    flag, the scene file's "quality", or `default` for a render without a scene file (a scene
    file's own settings are kept as they are unless a level is named); and why `auto` chose."""
    from volren.draw import resolve_scene

    if scene.volume is None or source is None:
        return scene, None
    return resolve_scene(scene, source, settings_level(args, scene), on_cluster=wants_cluster(args))


def settings_level(args: argparse.Namespace, scene: Scene) -> str | None:
    """The quality level whose settings the scene gets: the flag, the scene file's "quality", or
    `default` for a render without a scene file; None for a scene file's own settings."""
    named = args.quality or scene.extra.get("quality")
    return str(named) if named is not None else (None if args.scene else DEFAULT_LEVEL)


def quality_asked(args: argparse.Namespace, scene: Scene) -> str:
    """The quality level the frame is drawn at: the flag, the scene file's, else `default` (which
    pyramid level of an OME-Zarr INPUT is drawn depends on it: `ZarrInput.frame`)."""
    return str(args.quality or scene.extra.get("quality") or DEFAULT_LEVEL)


def check_outputs(outputs, inputs, force: bool) -> None:
    """Outputs never name the same file; without --force, none is an input either."""
    from volren.io.safe_write import refuse_overwriting_inputs

    refuse_overwriting_inputs(outputs, [] if force else inputs, hint=" (or add --force)")


def check_scene_input(args: argparse.Namespace, scene: Scene) -> None:
    """`volren.draw.check_scene`, naming what the user gave: the flag or the scene file."""
    from volren.draw import check_scene

    from_scene = args.scene and args.step is None
    step_name = f"{args.scene}: settings.step (or --step)" if from_scene else "--step"
    tf_name = args.tf or args.scene or "the default transfer function"
    if scene.volume is None:
        raise VolrenError(f"{args.scene}: the scene names no volume; give INPUT")
    check_scene(scene.volume, scene.transfer_function, scene.settings, tf_name, step_name)


def _naming_the_input(exc: VolrenError, source: str | None, chosen_renderer: str | None) -> VolrenError:
    """A rendering error about the data, with the file it came from in front, unless it names
    its culprit already: a file, a flag, or the renderer the command line chose (a renderer
    named by a scene file is the scene's fault): every message names what is at fault."""
    text = str(exc)
    named = Path(source).name in text if source else True
    if named or "--" in text or (chosen_renderer and f"renderer {chosen_renderer} " in f"{text} "):
        return exc
    return VolrenError(f"{source}: {text}")


def explained(exc: VolrenError, args: argparse.Namespace, scene: Scene, why: str | None) -> VolrenError:
    """A rendering error as the command line reports it: saying that `auto` chose the renderer
    when the user did not name it, and naming the input file where the message names nothing."""
    chosen = scene.renderer if args.renderer or not args.scene else None
    if why and f"renderer {scene.renderer} " in f"{exc} ":  # the user did not name it: say who did
        exc = VolrenError(
            f"{exc} ".replace(
                f"renderer {scene.renderer} ", f"renderer {scene.renderer} {CHOSEN_BY_AUTO} ", 1
            ).rstrip()
        )
    return _naming_the_input(exc, args.scene or scene.volume_path, chosen)


def run(args: argparse.Namespace) -> int:
    from volren import io
    from volren.io.safe_write import check_output

    if args.output == "" or args.save_array == "":
        raise VolrenError(f"{'-o' if args.output == '' else '--save-array'} needs a file name, got ''")
    if not args.output and not args.save_array:
        raise VolrenError("give -o OUT.png (and/or --save-array OUT.npy)")
    outputs = (("-o", args.output), ("--save-array", args.save_array))
    for flag, target in outputs:
        if target:
            check_output(target, flag)  # the folder a link leads to, too: before the render, not after
    inputs = [("input volume", args.input), ("--tf file", args.tf), ("--scene file", args.scene),
              ("--labels file", args.labels), ("--label-info file", args.label_info),
              *(("--channel-tf file", path) for _, path in args.channel_tf)]  # fmt: skip
    check_outputs(outputs, inputs, args.force)  # before the (maybe long) load
    check_cluster_flag(args)
    clock = StageClock()
    with clock.stage("load"):
        scene, why, source = build_scene(args)
        check_outputs(outputs, [*inputs, ("scene's volume", scene.volume_path)], args.force)
        check_scene_input(args, scene)
    assert source is not None  # a scene without a volume was refused above
    width, height = scene.size
    drawing = Drawing(source, scene, quality_asked(args, scene), args.cluster, args.scheduler)
    try:
        image, stats, drawn = drawing.frame(drawing.camera(), watch=_CommandWatch(clock))
        clock.note_counters(stats.counters)
    except VolrenError as exc:
        raise explained(exc, args, scene, why) from None
    with clock.stage("write"):
        if args.output:
            io.save_image(image, args.output, transparent=args.transparent)
        if args.save_array:
            io.save_array(image, args.save_array)
    if args.timings:
        print(f"volren: {clock.line()}", file=sys.stderr)
    written = " ".join(str(p) for p in (args.output, args.save_array) if p)
    chosen_by = f" (auto: {why})" if why else ""
    print(f"{scene.renderer}{chosen_by}: {width}x{height} in {stats.ms:.1f} ms{drawn} -> {written}")
    return 0


class _CommandWatch(Watch):
    """A frame's stages on the command's clock (--timings), its progress as a bar on a terminal."""

    def __init__(self, clock: StageClock) -> None:
        super().__init__()
        self.clock = clock

    def stage(self, name: str) -> AbstractContextManager[object]:
        return self.clock.stage(name)

    def progress(self, label: str) -> AbstractContextManager[ProgressCallback | None]:
        from volren.cli.progress import progress_bar

        return progress_bar(label)
