"""The channel flags of `volren render` and `volren movie`: a multi-channel volume drawn with a
transfer function per channel, their extinctions and emissions added (Max 1995, section 2).

    volren render brain.vti --channels [0,2] [--channel-tf 2=flair.json ...] [--channel-weight 0=2]
                  [--hide-channels 1]

``--channels`` alone reads every component of INPUT's array (or every channel of an OME-Zarr
image's c axis); with a list, those (the file's numbers, which the other flags name too). What they
make is `volren.draw.channels`' (the API's too): each channel's default ramp, or --tf for every
channel, or a TF file per channel (kind "channels"); then the per-channel TFs, weights and hidden
channels. Nothing heavy is imported when the parser is built.
"""

from __future__ import annotations

import argparse
import math
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from volren.errors import VolrenError

if TYPE_CHECKING:
    from volren.draw import DrawInput
    from volren.model.scene import Scene

#: The most channels a list names (`volren.model.channels.MAX_CHANNELS`, not imported here: the
#: parser is built without the model; the list is checked against it when the volume is read).
_LIST_LIMIT = 64


def channel_list(text: str) -> tuple[int, ...]:
    """An argparse type for --channels and --hide-channels: C,D,... whole numbers >= 0."""
    words = [w.strip() for w in text.split(",")]
    if len(words) > _LIST_LIMIT:
        raise argparse.ArgumentTypeError(f"at most {_LIST_LIMIT} channels, got {len(words)}")
    if not all(w.isdigit() for w in words):
        bad = next(w for w in words if not w.isdigit())
        raise argparse.ArgumentTypeError(
            f"expected channels C,D,... (whole numbers from 0), got {bad!r} in {text!r}"
        )
    return tuple(int(w) for w in words)


def _channel_item(text: str, what: str) -> tuple[int, str]:
    channel, sep, value = text.partition("=")
    if not sep or not value.strip():
        raise argparse.ArgumentTypeError(f"expected C={what}, got {text!r}")
    if not channel.strip().isdigit():
        raise argparse.ArgumentTypeError(
            f"the channel before '=' must be a whole number from 0, got {channel!r}"
        )
    return int(channel), value.strip()


def channel_tf_item(text: str) -> tuple[int, str]:
    """An argparse type for --channel-tf: C=TF.json, channel C drawn with that 1D TF."""
    return _channel_item(text, "TF.json (a channel and its transfer function)")


def channel_weight_item(text: str) -> tuple[int, float]:
    """An argparse type for --channel-weight: C=W, channel C's density scaled by W >= 0."""
    channel, value = _channel_item(text, "W (a channel and its weight)")
    try:
        weight = float(value)
    except ValueError:
        weight = -1.0
    if not (math.isfinite(weight) and weight >= 0):
        raise argparse.ArgumentTypeError(f"the weight after '=' must be a number >= 0, got {value!r}")
    return channel, weight


def add_channel_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--channels", nargs="?", const=True, type=channel_list, metavar="C,D,...",
                   help="draw INPUT's array components (or an OME-Zarr image's c axis) as channels, each with its own "
                        "transfer function, mixed in one ray march: all, or those listed (the file's numbers)")  # fmt: skip
    p.add_argument("--channel-tf", type=channel_tf_item, action="append", default=[], metavar="C=TF.json",
                   help="draw channel C with this 1D transfer function (repeatable)")  # fmt: skip
    p.add_argument("--channel-weight", type=channel_weight_item, action="append", default=[], metavar="C=W",
                   help="scale channel C's density by W >= 0 (default 1; repeatable)")  # fmt: skip
    p.add_argument("--hide-channels", type=channel_list, action="append", default=[], metavar="C,D,...",
                   help="do not draw these channels")  # fmt: skip


def channel_flag(args: argparse.Namespace) -> str | None:
    """The first channel flag given (None: none)."""
    given = (("--channels", args.channels is not None), ("--channel-tf", args.channel_tf),
             ("--channel-weight", args.channel_weight), ("--hide-channels", args.hide_channels))  # fmt: skip
    return next((flag for flag, value in given if value), None)


def pick_of(args: argparse.Namespace, scene_pick: Any = None) -> Any:
    """The channel pick: --channels (True: all, or the numbers), else the scene file's, else None."""
    return args.channels if args.channels is not None else scene_pick


def load_channel_input(args: argparse.Namespace, path: str, pick: Any) -> DrawInput:
    """INPUT (a file, or an OME-Zarr image within --memory at --level) read whole with the
    channels `pick` names; its errors name --channels (or the scene's pick)."""
    from volren import io
    from volren.cli.raw_flags import raw_load_arguments
    from volren.draw import VolumeInput, is_ome_zarr_path
    from volren.io.volume_io import load_ome_zarr

    flag = "--channels" if args.channels is not None else f"{args.scene}: channels"
    try:
        if is_ome_zarr_path(path) and not args.raw_shape:
            if args.scalars is not None:
                raise VolrenError(f"{path}: an OME-Zarr image holds one field; --scalars does not apply")
            return VolumeInput(load_ome_zarr(path, args.level, args.memory, pick))
        return VolumeInput(
            io.load_volume(path, scalars=args.scalars, channels=pick, **raw_load_arguments(args))
        )
    except VolrenError as exc:
        raise VolrenError(f"{flag}: {exc}") from None


def with_channel_flags(args: argparse.Namespace, scene: Scene, source: DrawInput | None,
                       on_cluster: bool = False) -> tuple[Scene, DrawInput | None]:  # fmt: skip
    """The scene with its multi-channel volume and TF per channel, from the flags and the scene
    file's own (`volume.channels`, a TF of kind "channels"); the scene and its input as they are
    where neither asks for channels. The drawing's modules are imported here."""
    from volren.cli.label_flags import label_flag
    from volren.draw import VolumeInput
    from volren.draw.channels import CLI_ARGS, channelled, wants_channels
    from volren.model.labels import LabelTransferFunction

    hidden = [c for group in args.hide_channels for c in group]
    tfs, weights = dict(args.channel_tf), dict(args.channel_weight)
    volume = scene.volume
    if volume is None or source is None:  # the scene names no volume: refused by the caller
        return scene, source
    if not wants_channels(volume, scene.transfer_function, args.channels, tfs, weights, hidden):
        return scene, source
    flag = channel_flag(args) or f"{args.scene}: channels"
    labelled = isinstance(scene.transfer_function, LabelTransferFunction) or scene.labels_path is not None
    if labelled or label_flag(args) or getattr(volume, "labels", None) is not None:
        raise VolrenError(f"{flag}: a volume is drawn with --labels or with --channels, not both at once yet")
    if source.bricks:
        raise VolrenError(f"{flag}: channels are drawn from a volume read whole, not from an OME-Zarr image "
                          "streamed by bricks")  # fmt: skip
    if on_cluster:
        raise VolrenError(f"{flag}: multi-channel volumes are not drawn on a cluster")
    # --tf's or the scene's TF: a TF per channel, or a 1D TF for every channel (a 2D one refused there);
    # with neither, the default is already the channels' own (`as_transfer_function`)
    volume, ctf = channelled(volume, scene.transfer_function, tfs, weights, hidden, CLI_ARGS)  # type: ignore[arg-type]
    pick = pick_of(args, scene.channels)
    scene = replace(scene, volume=volume, transfer_function=ctf, channels=pick)
    return scene, VolumeInput(volume)
