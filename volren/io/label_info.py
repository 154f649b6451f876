"""Label-info files: what a segmentation's labels are called and how each is drawn.

A label volume holds numbers; which organ each number is, and the transfer function it is drawn
with (Real-Time Volume Graphics, chapter 16: a TF per object), come from beside it::

    {"version": 1, "labels": {"3": {"name": "liver", "color": [0.8, 0.3, 0.2], "opacity": 0.5,
                                     "visible": true, "tf": "bone.json"}}}

The labels may also be a list, ``[{"value": 3, "name": "liver", ...}, ...]``, and the version left
out (version 1). Every key of a label is optional. Names and colours describe the labels (`LabelMap.names` and
`colors`); "color", "opacity", "visible" and "tf" (a TF file, relative to this file's folder, or
an inline 1D TF) are the label's `LabelStyle`, over the look the label has without them.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path
from typing import Any

from volren.errors import VolrenError, file_error
from volren.io.json_text import read_json
from volren.io.tf_io import load_transfer_function
from volren.model.file_version import check_format_version
from volren.model.labels import LabelStyle, parse_label
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import transfer_function_from_dict

LABEL_INFO_VERSION = 1
_KEYS = frozenset({"name", "color", "opacity", "visible", "tf"})


@dataclass(frozen=True)
class LabelInfo:
    """Names and colours of labels, and the style fields given for each (`LabelStyle`'s visible,
    color, opacity, tf: only those the file names, to go over the label's default look)."""

    names: Mapping[int, str] = field(default_factory=dict)
    colors: Mapping[int, tuple[float, float, float]] = field(default_factory=dict)
    styles: Mapping[int, Mapping[str, Any]] = field(default_factory=dict)


def one_d_tf(value: object, what: str, folder: Path | None = None) -> TransferFunction1D:
    """A label's 1D TF from a TF, a TF file (relative to `folder`) or an inline TF dict."""
    if isinstance(value, str | PathLike):
        path = Path(value)
        tf = load_transfer_function(folder / path if folder is not None and not path.is_absolute() else path)
    elif isinstance(value, Mapping):
        tf = transfer_function_from_dict(value)
    else:
        tf = value  # type: ignore[assignment]
    if not isinstance(tf, TransferFunction1D):
        kind = "a 2D TF" if getattr(tf, "dims", None) == 2 else f"a {type(tf).__name__}"
        raise VolrenError(f"{what}: a label's transfer function is 1D, got {kind}")
    return tf


def _listed(entries: list[Any]) -> dict[Any, Any]:
    """The list form, ``[{"value": 3, "name": ..., "color": ...}, ...]`` (as NAME.labels.json files
    beside segmentations often give it), as the object form."""
    out: dict[Any, Any] = {}
    for n, entry in enumerate(entries):
        if not isinstance(entry, Mapping) or "value" not in entry:
            raise VolrenError(
                f"labels[{n}]: a listed label is an object with a 'value' (and name, color, ...)"
            )
        label = parse_label(entry["value"], f"labels[{n}]")
        if label in out:
            raise VolrenError(f"labels[{n}]: label {label} is listed twice")
        out[label] = {k: v for k, v in entry.items() if k != "value"}
    return out


def label_info_from_dict(data: Any, folder: Path | None = None) -> LabelInfo:
    """The label info of parsed JSON; TF paths relative to `folder` (the file's)."""
    check_format_version(data, "label info", LABEL_INFO_VERSION, default=LABEL_INFO_VERSION)
    unknown = set(data) - {"version", "labels"}
    if unknown:
        raise VolrenError(
            f"unknown key(s) {', '.join(sorted(unknown))}; a label info has 'version' and 'labels'"
        )
    entries = data.get("labels", {})
    if isinstance(entries, list):
        entries = _listed(entries)
    if not isinstance(entries, Mapping):
        raise VolrenError(
            f"'labels' must be an object of label: {{name, color, ...}}, got {type(entries).__name__}"
        )
    names: dict[int, str] = {}
    colors: dict[int, tuple[float, float, float]] = {}
    styles: dict[int, dict[str, Any]] = {}
    for key, entry in entries.items():
        label = parse_label(key, "labels")
        what = f"label {label}"
        if not isinstance(entry, Mapping):
            raise VolrenError(f"{what}: must be an object (name, color, opacity, visible, tf)")
        extra = set(entry) - _KEYS
        if extra:
            raise VolrenError(
                f"{what}: unknown key(s) {', '.join(sorted(extra))}; use {', '.join(sorted(_KEYS))}"
            )
        if entry.get("name") is not None:
            if not isinstance(entry["name"], str):
                raise VolrenError(f"{what}: 'name' must be text, got {entry['name']!r}")
            names[label] = entry["name"]
        given = {k: v for k, v in entry.items() if k in ("color", "opacity", "visible") and v is not None}
        if entry.get("tf") is not None:
            try:
                given["tf"] = one_d_tf(entry["tf"], f"{what}: tf", folder).to_dict()
            except VolrenError as exc:
                raise VolrenError(f"{what}: tf: {exc}" if f"{what}:" not in str(exc) else str(exc)) from None
        style = LabelStyle.from_dict(given, what)  # checks the fields, one line each
        fields = {k: getattr(style, k) for k in given}
        if style.color is not None:
            colors[label] = style.color
        if fields:
            styles[label] = fields
    return LabelInfo(names, colors, styles)


def load_label_info(path: str | PathLike[str]) -> LabelInfo:
    """A label-info JSON file (see the module docstring); every error is one line naming it."""
    path = Path(path)
    data = read_json(path)
    try:
        return label_info_from_dict(data, path.parent)
    except VolrenError as exc:
        text = str(exc)
        raise (exc if str(path) in text else file_error(path, text)) from None
