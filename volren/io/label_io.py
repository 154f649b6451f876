"""Label volumes (segmentations) from files, on the grid of the volume they segment.

A segmentation is read like any volume (`load_volume`: every grid format, its header checks and
one-line errors), then checked to be a label map (Real-Time Volume Graphics, chapter 16: one
object id per voxel, never interpolated as a number): whole numbers in 0..`MAX_LABEL`, one
component, on the intensity volume's grid. 3D Slicer's ``.seg.nrrd`` brings its segments' names,
colours and label values in ``SegmentN_*`` header keys, which are read too, and an OME-Zarr
image-label (``image.zarr/labels/NAME``: `volren.io.ome_zarr_labels`) its ``image-label`` colours and
properties.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from volren.errors import VolrenError, file_error
from volren.io.formats.base import read_head
from volren.io.ome_zarr_io import is_ome_zarr
from volren.io.ome_zarr_labels import load_label_image
from volren.io.volume_io import load_volume
from volren.model.labels import MAX_LABEL, LabelMap
from volren.model.volume import TetVolume, UniformVolume

#: Spacings that differ by at most this fraction are the same (NIfTI keeps float32, other tools
#: print six digits: 0.976562 for 0.9765625 is off by 5e-7).
SPACING_TOLERANCE = 1e-4
#: Origins that differ by at most this fraction of a voxel are the same: a sample moved by a
#: hundredth of a voxel is drawn where it was.
ORIGIN_TOLERANCE = 1e-2
_HEADER_LIMIT = 1 << 20
_SEGMENT_KEY = re.compile(r"Segment(\d+)_(\w+)$")


def load_labels(path: str | Path, volume: UniformVolume) -> LabelMap:
    """The label map in the file at `path` for `volume` (a uniform grid): its values checked to be
    whole numbers in 0..MAX_LABEL on the volume's grid, and, for a 3D Slicer ``.seg.nrrd``, its
    segments' names and colours. Every refusal is one line naming the file."""
    path = Path(path)
    names: dict[int, str] = {}
    colors: dict[int, tuple[float, float, float]] = {}
    if path.is_file() and path.name.lower().endswith((".nrrd", ".nhdr")):
        names, colors = slicer_segments(path)
    read: UniformVolume | TetVolume
    if is_ome_zarr(path):  # an OME-Zarr label image, or the labels group (or image) that has one
        read, names, colors, where = load_label_image(path)
        path = Path(where)
    else:
        read = load_volume(path)
    if not isinstance(read, UniformVolume):
        raise file_error(path, "is a tetrahedral mesh; a label volume is a uniform grid on the volume's grid")
    if read.scalars.endswith(":magnitude"):
        field = read.scalars.rpartition(":")[0]
        raise file_error(path, f"array {field!r} has several components; a label volume has one per voxel")
    check_same_grid(path, read, volume)
    try:
        return LabelMap(read.values, names, colors, name=path.name)
    except VolrenError as exc:
        text = str(exc)
        raise (exc if path.name in text else file_error(path, text)) from None


def _size(dims: Sequence[int]) -> str:
    return "x".join(str(n) for n in dims)


def _triple(values: Sequence[float]) -> str:
    return "(" + ", ".join(f"{v:g}" for v in values) + ")"


def check_same_grid(path: Path, labels: UniformVolume, volume: UniformVolume) -> None:
    """Refuse (one line naming the file, with both grids) labels on another grid than `volume`'s:
    other dimensions, spacings beyond `SPACING_TOLERANCE`, origins beyond `ORIGIN_TOLERANCE` of a
    voxel, or other anatomical axes where both files say."""
    if labels.dimensions != volume.dimensions:
        raise file_error(path, f"the label volume is {_size(labels.dimensions)} but {volume.name} is "
                               f"{_size(volume.dimensions)}: labels must lie on the volume's grid")  # fmt: skip
    if any(abs(a - b) > SPACING_TOLERANCE * b for a, b in zip(labels.spacing, volume.spacing)):
        raise file_error(path, f"the label volume's spacing {_triple(labels.spacing)} differs from "
                               f"{volume.name}'s {_triple(volume.spacing)}: labels must lie on the volume's grid")  # fmt: skip
    if any(
        abs(a - b) > ORIGIN_TOLERANCE * s for a, b, s in zip(labels.origin, volume.origin, volume.spacing)
    ):
        raise file_error(path, f"the label volume's origin {_triple(labels.origin)} differs from "
                               f"{volume.name}'s {_triple(volume.origin)}: labels must lie on the volume's grid")  # fmt: skip
    if labels.patient_axes and volume.patient_axes and labels.patient_axes != volume.patient_axes:
        theirs, ours = "".join(labels.patient_axes), "".join(volume.patient_axes)
        raise file_error(path, f"the label volume's axes point to {theirs} but {volume.name}'s to {ours}: "
                               "labels must lie on the volume's grid")  # fmt: skip


def nrrd_key_values(path: Path) -> dict[str, str]:
    """A NRRD header's ``key:=value`` lines (free-form metadata, which volren's NRRD reading skips)."""
    head = read_head(path, _HEADER_LIMIT)
    out: dict[str, str] = {}
    for number, raw in enumerate(head.split(b"\n")):
        line = raw.decode("latin-1").rstrip("\r")
        if number > 0 and not line:
            break  # the blank line that ends the header
        key, sep, value = line.partition(":=")
        if sep and not line.startswith("#"):
            out[key.strip()] = value.strip()
    return out


def _header_fields(path: Path) -> dict[str, str]:
    """The NRRD header's ``field: value`` lines (keys lower-cased, spaces removed)."""
    head = read_head(path, _HEADER_LIMIT)
    out: dict[str, str] = {}
    for number, raw in enumerate(head.split(b"\n")):
        line = raw.decode("latin-1").rstrip("\r")
        if number > 0 and not line:
            break
        key, sep, value = line.partition(": ")
        if sep and ":=" not in line and not line.startswith("#"):
            out[key.strip().lower().replace(" ", "")] = value.strip()
    return out


def slicer_segments(path: Path) -> tuple[dict[int, str], dict[int, tuple[float, float, float]]]:
    """({label: name}, {label: colour}) from 3D Slicer's ``SegmentN_Name``, ``SegmentN_Color``
    ("r g b" in [0, 1]) and ``SegmentN_LabelValue`` header keys (empty for another NRRD). A file
    of several layers (overlapping segments, a 4D file) is refused: a label volume holds one label
    per voxel."""
    keys = nrrd_key_values(path)
    segments: dict[int, dict[str, str]] = {}
    for key, value in keys.items():
        match = _SEGMENT_KEY.match(key)
        if match:
            segments.setdefault(int(match.group(1)), {})[match.group(2)] = value
    fields = _header_fields(path)
    sizes = fields.get("sizes", "").split()
    layers = {s.get("Layer", "0") for s in segments.values()}
    if len(sizes) > 3 and not segments:
        raise file_error(path, f"a NRRD of {len(sizes)} axes; a label volume has 3")
    if len(sizes) > 3 or len(layers) > 1:
        count = sizes[0] if len(sizes) > 3 else str(len(layers))
        raise file_error(path, f"a segmentation of {count} layers (overlapping segments); volren draws one label "
                               "per voxel: save it with one layer (3D Slicer: Segmentations > Collapse to one "
                               "layer)")  # fmt: skip
    names: dict[int, str] = {}
    colors: dict[int, tuple[float, float, float]] = {}
    for index, segment in sorted(segments.items()):
        given = segment.get("LabelValue")
        if given is None and len(segments) > 1:
            raise file_error(path, f"Segment{index}_LabelValue is missing (each segment needs its label)")
        value = (
            "1" if given is None else given
        )  # one segment without a value: an old one-layer file, marked 1
        try:
            label = int(value)
        except ValueError:
            label = -1
        if not 0 <= label <= MAX_LABEL:
            raise file_error(
                path, f"Segment{index}_LabelValue {value!r} is not a whole number in 0..{MAX_LABEL}"
            )
        if "Name" in segment:
            names[label] = segment["Name"]
        if "Color" in segment:
            colors[label] = _segment_color(path, index, segment["Color"])
    return names, colors


def _segment_color(path: Path, index: int, text: str) -> tuple[float, float, float]:
    try:
        rgb = [float(v) for v in text.split()]
    except ValueError:
        rgb = []
    if len(rgb) != 3 or not all(math.isfinite(v) and 0 <= v <= 1 for v in rgb):
        raise file_error(path, f"Segment{index}_Color {text!r} must be three numbers in [0, 1]")
    return (rgb[0], rgb[1], rgb[2])


def label_array(values: object, volume: UniformVolume, what: str = "labels") -> LabelMap:
    """A label map from labels in memory (an array indexed [k, j, i] as the volume's values, or a
    `LabelMap`), checked to lie on `volume`'s grid; errors name `what`."""
    label_map = values if isinstance(values, LabelMap) else LabelMap(np.asarray(values), name=what)
    label_map.check_grid(volume.values.shape, volume.name)
    return label_map
