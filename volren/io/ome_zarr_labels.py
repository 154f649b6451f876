"""OME-Zarr image-label groups: the segmentations stored beside an OME-Zarr image.

NGFF (0.4 and 0.5, "labels" and "image-label" metadata): an image's ``labels/`` group lists its label
images (``{"labels": ["organs", ...]}``); each is a multiscale image of whole numbers on the image's
grid whose ``image-label`` metadata gives ``colors`` (``{"label-value": 3, "rgba": [r, g, b, a]}``,
0..255) and ``properties`` (``{"label-value": 3, "class": "liver", ...}``, free keys). Its finest
level is read as a `LabelMap` (Real-Time Volume Graphics, chapter 16: one object id per voxel), with
the names (a property "name", else the spec's example key "class") and the colours (rgb; the
alpha is left to the label's TF). Malformed colours or properties are passed over, as viewers
write them loosely; the label values themselves are checked like every label volume's.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from volren.errors import VolrenError
from volren.io import ome_zarr_io
from volren.model.labels import MAX_LABEL
from volren.model.volume import UniformVolume

#: The property keys read as a label's name, first found first.
NAME_KEYS = ("name", "class")


def _attrs(where: str) -> dict[str, Any]:
    """The attributes of the Zarr group at `where` (NGFF 0.5 keeps them under "ome"), or a
    one-line error naming it."""
    zarr = ome_zarr_io.require_zarr()
    try:
        attrs = dict(zarr.open_group(where, mode="r").attrs)
    except ome_zarr_io._read_errors() as exc:
        raise VolrenError(f"{where}: not a readable Zarr group: {ome_zarr_io.read_problem(exc)}") from None
    ome = attrs.get("ome")
    return {**attrs, **ome} if isinstance(ome, Mapping) else attrs


def listed_labels(where: str | Path) -> tuple[str, ...]:
    """The label images a ``labels`` group lists (its "labels" key); () where it lists none."""
    listed = _attrs(str(where)).get("labels")
    if not isinstance(listed, list):
        return ()
    return tuple(str(n) for n in listed if isinstance(n, str) and n)


def image_labels(image: str | Path) -> tuple[str, ...]:
    """The label images offered beside the OME-Zarr image at `image` (paths ``IMAGE/labels/NAME``);
    () without a ``labels`` group."""
    folder = Path(str(image)) / "labels"
    if not ome_zarr_io.is_ome_zarr(folder):
        return ()
    return tuple(str(folder / name) for name in listed_labels(folder))


def label_image_path(path: str | Path) -> str:
    """The label image `path` names: a label image itself; a ``labels`` group listing exactly one;
    or an image whose ``labels`` group lists exactly one. Several: a one-line error listing them."""
    where = str(path).rstrip("/")
    attrs = _attrs(where)
    if "multiscales" in attrs and ("image-label" in attrs or not image_labels(where)):
        return where
    group = where if "multiscales" not in attrs else f"{where}/labels"
    names = listed_labels(group)
    if not names:
        raise VolrenError(f"{where}: an OME-Zarr labels group must list its label images under 'labels'")
    if len(names) > 1:
        shown = ", ".join(f"{group}/{n}" for n in names)
        raise VolrenError(f"{where}: {len(names)} label images ({shown}); name one")
    return f"{group}/{names[0]}"


def _label_value(entry: Mapping[str, Any]) -> int | None:
    value = entry.get("label-value")
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= MAX_LABEL:
        return None
    return value


def _rgb(rgba: Any) -> tuple[float, float, float] | None:
    """The rgb of an image-label rgba (four whole numbers 0..255); None where malformed."""
    numeric = (
        isinstance(rgba, list)
        and len(rgba) in (3, 4)
        and all(isinstance(v, int) and not isinstance(v, bool) and 0 <= v <= 255 for v in rgba)
    )
    return (rgba[0] / 255.0, rgba[1] / 255.0, rgba[2] / 255.0) if numeric else None


def label_hints(meta: Any) -> tuple[dict[int, str], dict[int, tuple[float, float, float]]]:
    """({label: name}, {label: colour}) from ``image-label`` metadata (entries that are malformed
    passed over)."""
    names: dict[int, str] = {}
    colors: dict[int, tuple[float, float, float]] = {}
    if not isinstance(meta, Mapping):
        return names, colors
    for entry in meta.get("colors") or []:
        if isinstance(entry, Mapping) and (label := _label_value(entry)) is not None:
            if (rgb := _rgb(entry.get("rgba"))) is not None:
                colors[label] = rgb
    for entry in meta.get("properties") or []:
        if isinstance(entry, Mapping) and (label := _label_value(entry)) is not None:
            name = next((entry[k] for k in NAME_KEYS if isinstance(entry.get(k), str | int)), None)
            if name is not None and str(name):
                names[label] = str(name)
    return names, colors


def load_label_image(
    path: str | Path,
) -> tuple[UniformVolume, dict[int, str], dict[int, tuple[float, float, float]], str]:
    """(the finest level of the label image `path` names (`label_image_path`), its names, its
    colours, its path): the values as stored, for `volren.io.label_io` to check on the volume's grid."""
    where = label_image_path(path)
    names, colors = label_hints(_attrs(where).get("image-label"))
    volume = ome_zarr_io.load_level(where, 0, name=Path(where).name)
    return volume, names, colors, where
