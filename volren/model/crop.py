"""Axis-aligned cropping: the part of a volume inside a box, as a volume every renderer can draw.

Cropping makes a smaller volume rather than asking each renderer to clip: the result is exact for
every renderer (plugins included), the renderers skip the cropped-away data for free, and the
crop box means the same thing on uniform grids and on meshes. A uniform grid keeps the samples
inside the box (at least two per axis, so it stays a grid; the box snaps outwards to whole
samples); a mesh keeps the tetrahedra whose four corners are inside the box (ParaView's
"extract cells by region" with "all points inside").
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import cast

import numpy as np

from volren.errors import VolrenError
from volren.model.clip_region import Box, check_box
from volren.model.volume import TetVolume, UniformVolume, Volume


def covers(box: Box, bounds: Sequence[float]) -> bool:
    """True when the box contains the whole of `bounds` (cropping would change nothing)."""
    return all(box[2 * a] <= bounds[2 * a] and box[2 * a + 1] >= bounds[2 * a + 1] for a in range(3))


def _index_range(lo: float, hi: float, origin: float, spacing: float, n: int) -> tuple[int, int]:
    """First and one-past-last sample index inside [lo, hi], widened to at least two samples."""
    eps = 1e-9
    first = max(0, math.floor((lo - origin) / spacing + eps))
    last = min(n - 1, math.ceil((hi - origin) / spacing - eps))
    if last - first < 1:  # keep a grid: two samples around the box
        first = min(max(0, first), n - 2)
        last = first + 1
    return first, last + 1


def crop_volume(volume: Volume, box: Sequence[float]) -> Volume:
    """The part of `volume` inside `box`; the volume itself when the box covers it all."""
    box = check_box(box)
    if covers(box, volume.bounds):
        return volume
    if isinstance(volume, UniformVolume):
        return _crop_uniform(volume, box)
    return _crop_mesh(volume, box)


def cropped_dimensions(volume: UniformVolume, box: Sequence[float]) -> tuple[int, int, int]:
    """The (nx, ny, nz) samples `crop_volume` keeps of a grid, without cutting it (no copy of its values)."""
    first_stop = _index_ranges(volume, check_box(box))
    return cast(tuple[int, int, int], tuple(stop - first for first, stop in first_stop))


def _index_ranges(volume: UniformVolume, box: Box) -> list[tuple[int, int]]:
    """(first, one past last) sample index inside the box along x, y and z."""
    nz, ny, nx = volume.values.shape
    return [_index_range(box[2 * axis], box[2 * axis + 1], volume.origin[axis], volume.spacing[axis], n)
            for axis, n in zip(range(3), (nx, ny, nz), strict=True)]  # fmt: skip


def _crop_uniform(volume: UniformVolume, box: Box) -> UniformVolume:
    ranges = _index_ranges(volume, box)
    sx, sy, sz = (slice(first, stop) for first, stop in ranges)
    origin = tuple(volume.origin[axis] + ranges[axis][0] * volume.spacing[axis] for axis in range(3))
    labels = channels = None
    if volume.labels is not None:  # the segmentation and the channels are cut with the values
        labels = replace(volume.labels, values=volume.labels.values[sz, sy, sx])
    if volume.channels is not None:
        channels = replace(volume.channels, values=volume.channels.values[:, sz, sy, sx])
    return UniformVolume(
        volume.values[sz, sy, sx],
        spacing=volume.spacing,
        origin=cast(tuple[float, float, float], origin),
        name=volume.name,
        labels=labels,
        channels=channels,
    )


def _crop_mesh(volume: TetVolume, box: Box) -> TetVolume:
    lo = np.array(box[0::2])
    hi = np.array(box[1::2])
    inside = np.all((volume.points >= lo) & (volume.points <= hi), axis=1)
    keep = np.all(inside[volume.tets], axis=1)
    if not keep.any():
        raise VolrenError(f"{volume.name}: no tetrahedron lies wholly inside the crop box {box}")
    tets = volume.tets[keep]
    used = np.unique(tets)
    remap = np.full(len(volume.points), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    return TetVolume(volume.points[used], remap[tets], volume.values[used], name=volume.name)
