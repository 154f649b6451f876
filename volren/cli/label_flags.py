"""The label flags of `volren render` and `volren movie`: a segmentation drawn with a transfer
function per label (Real-Time Volume Graphics, chapter 16).

    volren render CT.nii.gz --labels seg.nii.gz [--label-info labels.json] [--label-tf 3=bone.json ...]
                  [--hide-labels 0,7]

An OME-Zarr INPUT with labels (its own label image: ``--labels image.zarr/labels/NAME``) is read
whole at full resolution, where label images lie, instead of streamed by bricks.

What they make is `volren.draw.labelled`'s (the API's too): each label in the volume's TF
recoloured (label 0 as it is), then the label info, then the per-label TFs, then the hidden labels.
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from typing import TYPE_CHECKING

from volren.errors import VolrenError
from volren.model.labels import MAX_LABEL, parse_label

if TYPE_CHECKING:
    from volren.draw import DrawInput
    from volren.model.scene import Scene
    from volren.model.volume import UniformVolume


def label_tf_item(text: str) -> tuple[int, str]:
    """An argparse type for --label-tf: N=TF.json, label N drawn with that TF."""
    label, sep, path = text.partition("=")
    if not sep or not path.strip():
        raise argparse.ArgumentTypeError(
            f"expected N=TF.json (a label and its transfer function), got {text!r}"
        )
    try:
        return parse_label(label, "label"), path
    except VolrenError:
        raise argparse.ArgumentTypeError(
            f"the label before '=' must be a whole number in 0..{MAX_LABEL}, got {label!r}"
        ) from None


def label_list(text: str) -> tuple[int, ...]:
    """An argparse type for --hide-labels: N,M,... whole numbers in 0..MAX_LABEL."""
    words = [w.strip() for w in text.split(",")]
    labels = []
    for word in words:
        try:
            labels.append(parse_label(word, "label"))
        except VolrenError:
            raise argparse.ArgumentTypeError(
                f"expected labels N,M,... (whole numbers in 0..{MAX_LABEL}), got {word!r} in {text!r}"
            ) from None
    return tuple(labels)


def add_label_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--labels", metavar="SEG",
                   help="a segmentation on INPUT's grid (NIfTI, NRRD or 3D Slicer's .seg.nrrd, MetaImage, .vti, an OME-Zarr "
                        "label image IMAGE.zarr/labels/NAME, ...: "
                        "whole numbers 0..65535): each label drawn with its own transfer function, by default the "
                        "volume's TF in the label's colour (label 0 as the TF is)")  # fmt: skip
    p.add_argument("--label-info", metavar="LABELS.json",
                   help='names and looks of the labels: {"version": 1, "labels": {"3": {"name": "liver", "color": '
                        '[r, g, b], "opacity": 0.5, "visible": true, "tf": "bone.json"}}}')  # fmt: skip
    p.add_argument("--label-tf", type=label_tf_item, action="append", default=[], metavar="N=TF.json",
                   help="draw label N with this 1D transfer function, in its own colours (repeatable)")  # fmt: skip
    p.add_argument("--hide-labels", type=label_list, action="append", default=[], metavar="N,M,...",
                   help="do not draw these labels (e.g. 0 for the background)")  # fmt: skip


def label_flag(args: argparse.Namespace) -> str | None:
    """The first label flag given (None: none)."""
    given = (("--labels", args.labels), ("--label-info", args.label_info), ("--label-tf", args.label_tf),
             ("--hide-labels", args.hide_labels))  # fmt: skip
    return next((flag for flag, value in given if value), None)


def with_label_flags(args: argparse.Namespace, scene: Scene, source: DrawInput | None,
                     on_cluster: bool = False) -> tuple[Scene, DrawInput | None]:  # fmt: skip
    """The scene with its label volume and TF per label, from the flags and the scene file's own
    (`volume.labels`, a TF of kind "labels"); the scene and its input as they are where neither
    asks for labels. The drawing's modules are imported here, not when the parser is built."""
    from volren.draw import VolumeInput
    from volren.draw.labelled import CLI_ARGS, labelled, wants_labels

    hidden = [label for group in args.hide_labels for label in group]
    tfs = dict(args.label_tf)
    volume = scene.volume
    if volume is None or source is None:  # the scene names no volume: refused by the caller
        return scene, source
    labels, names = args.labels, CLI_ARGS
    if labels is None and getattr(volume, "labels", None) is None and scene.labels_path is not None:
        labels = scene.labels_path  # a scene file's labels, for the INPUT given instead of its volume
        names = replace(CLI_ARGS, labels=f"{args.scene}: labels")
    if not wants_labels(volume, scene.transfer_function, labels, args.label_info, tfs, hidden):
        return scene, source
    flag = label_flag(args) or "--labels"
    if on_cluster:
        raise VolrenError(f"{flag}: label volumes are not drawn on a cluster")
    if source.bricks:  # labels are drawn from a volume read whole: the image's full resolution
        volume = _whole_image(args, flag)
    volume, tf = labelled(volume, scene.transfer_function, labels, args.label_info, tfs, hidden, names)  # type: ignore[arg-type]
    scene = replace(scene, volume=volume, transfer_function=tf, labels_path=labels or scene.labels_path)
    return scene, VolumeInput(volume)


def _whole_image(args: argparse.Namespace, flag: str) -> UniformVolume:
    """An OME-Zarr INPUT (or its time step) read whole at full resolution, where its label images
    lie (NGFF: a label image has its image's grid); within --memory, else one line naming `flag`."""
    from volren.cli.time_steps import step_path
    from volren.io.volume_io import load_ome_zarr

    if args.level not in (None, 0):
        raise VolrenError(
            f"{flag}: labels lie on the image's full resolution; --level {args.level} does not apply"
        )
    try:
        return load_ome_zarr(step_path(args), 0, args.memory)
    except VolrenError as exc:
        raise VolrenError(f"{flag}: {exc}") from None
