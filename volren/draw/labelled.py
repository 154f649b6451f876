"""A scene with a label volume: the volume given its `LabelMap` and the TF made a
`LabelTransferFunction` (Real-Time Volume Graphics, chapter 16: a TF per label), the one way
`volren.render`, `volren render` and scene files put labels, label info, per-label TFs and hidden
labels together.

The order, each step over the one before: the label volume's default look over the volume's TF
(`LabelTransferFunction.for_labels`: label 0 in the volume's TF, the others in their file's or the
palette's colour), or the `LabelTransferFunction` given; then the label info's styles; then the
per-label TFs; then the hidden labels.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sized
from dataclasses import dataclass, replace
from os import PathLike
from pathlib import Path
from typing import Any

from volren.errors import VolrenError
from volren.io.label_info import LabelInfo, label_info_from_dict, load_label_info, one_d_tf, parse_label
from volren.io.label_io import label_array, load_labels
from volren.model.labels import LabelMap, LabelTransferFunction
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TransferFunction
from volren.model.volume import UniformVolume, Volume


@dataclass(frozen=True)
class LabelArgs:
    """How the caller names each label input in errors (the API's arguments, or the CLI's flags)."""

    labels: str = "labels"
    info: str = "label_info"
    tfs: str = "label_tfs"
    hidden: str = "hidden_labels"


API_ARGS = LabelArgs()
CLI_ARGS = LabelArgs("--labels", "--label-info", "--label-tf", "--hide-labels")


def _named(exc: VolrenError, name: str) -> VolrenError:
    """`exc` with the argument `name` in front, unless it names it already."""
    text = str(exc)
    return exc if text.startswith(name) else VolrenError(f"{name}: {text}")


def wants_labels(volume: Volume, tf: object, labels: object = None, info: object = None,
                 tfs: Mapping[Any, Any] | None = None, hidden: Iterable[Any] = ()) -> bool:  # fmt: skip
    """Whether anything asks for a label scene: a label input, a `LabelTransferFunction`, or a
    volume that has labels."""
    given = labels is not None or info is not None or _given(tfs) or _given(hidden)
    return given or isinstance(tf, LabelTransferFunction) or getattr(volume, "labels", None) is not None


def _given(value: object) -> bool:
    """Whether an optional collection was given: not None and not empty (anything else, an iterator
    or a wrong type, counts as given, for `labelled` to check)."""
    if value is None:
        return False
    return len(value) > 0 if isinstance(value, Sized) else True


def labelled(
    volume: Volume,
    tf: TransferFunction | LabelTransferFunction,
    labels: str | PathLike | LabelMap | Any = None,
    info: str | PathLike | Mapping[str, Any] | LabelInfo | None = None,
    tfs: Mapping[Any, Any] | None = None,
    hidden: Iterable[Any] = (),
    names: LabelArgs = API_ARGS,
) -> tuple[UniformVolume, LabelTransferFunction]:
    """(the volume with its labels, the TF per label). `labels`: a segmentation file (`load_labels`),
    an array indexed [k, j, i] or a `LabelMap`; None: the volume's own. `info`: a label-info file
    or dict (`volren.io.label_info`); `tfs`: {label: a 1D TF, TF file or TF dict}; `hidden`: labels
    not drawn. Errors are one line naming the argument as `names` says."""
    if not isinstance(volume, UniformVolume):
        raise VolrenError(
            f"{names.labels}: label volumes are for uniform grids; {volume.name} is a tetrahedral mesh"
        )
    if isinstance(hidden, str | bytes) or not isinstance(hidden, Iterable):
        raise VolrenError(f"{names.hidden}: give the labels as a list of whole numbers, got {hidden!r}")
    hidden = tuple(hidden)
    if tfs is not None and not isinstance(tfs, Mapping):
        raise VolrenError(f"{names.tfs}: give {{label: transfer function}}, got a {type(tfs).__name__}")
    asked = names.info if info is not None else names.tfs if tfs else names.hidden if hidden else None
    label_map = _label_map(volume, labels, asked or "a transfer function per label", names)
    label_info = _label_info(info, names)
    if label_info is not None:
        label_map = LabelMap(label_map.values, {**label_map.names, **label_info.names},
                             {**label_map.colors, **label_info.colors}, name=label_map.name)  # fmt: skip
    if volume.labels is not label_map:
        volume = replace(volume, labels=label_map)
    if isinstance(tf, LabelTransferFunction):
        ltf = tf.copy()
    elif isinstance(tf, TransferFunction1D):
        ltf = LabelTransferFunction.for_labels(tf, label_map)
    else:
        raise VolrenError(f"{names.labels}: labels draw with a 1D transfer function per label; got a 2D one")
    given = dict(label_info.styles) if label_info is not None else {}
    for label, fields in given.items():
        fields = dict(fields)
        if "tf" in fields and "color" not in fields:
            fields["color"] = None  # its own TF: in its own colours
        ltf.set_style(label, replace(ltf.style(label), **fields))
    for key, value in dict(tfs or {}).items():
        label = parse_label(key, names.tfs)
        try:
            label_tf = one_d_tf(value, f"label {label}")
        except VolrenError as exc:
            raise _named(exc, names.tfs) from None
        color = given.get(label, {}).get("color")
        ltf.set_style(label, replace(ltf.style(label), tf=label_tf, color=color))
    ltf.hide([parse_label(label, names.hidden) for label in hidden])
    return volume, ltf


def _label_map(volume: UniformVolume, labels: object, asked: str, names: LabelArgs) -> LabelMap:
    """The label map given (a file, an array, a `LabelMap`), or the volume's own; `asked`: what
    asked for labels, named where there are none."""
    if labels is None:
        if volume.labels is None:
            raise VolrenError(f"{asked} needs a label volume: give {names.labels}")
        return volume.labels
    try:
        if isinstance(labels, str | PathLike):
            return load_labels(Path(labels), volume)
        return label_array(labels, volume, names.labels)
    except VolrenError as exc:
        raise _named(exc, names.labels) from None


def _label_info(info: object, names: LabelArgs) -> LabelInfo | None:
    try:
        if info is None or isinstance(info, LabelInfo):
            return info
        if isinstance(info, str | PathLike):
            return load_label_info(info)
        if isinstance(info, Mapping):
            return label_info_from_dict(info)
    except VolrenError as exc:
        raise _named(exc, names.info) from None
    raise VolrenError(f"{names.info}: give a label-info JSON file or dict, got a {type(info).__name__}")
