"""Picking a label: which label of a segmentation a pixel of the view shows first (no Qt).

Why: a click on a structure in the image should select it in the Labels panel (as 3D Slicer's and
ITK-SNAP's segment pickers do), so the person edits the label they see instead of hunting for its
name. A label map assigns each grid point an object id (Real-Time Volume Graphics, chapter 16);
the point's label holds in its voxel, the box of half a spacing around it (the nearest grid point).

The ray is the renderers' ray through the centre of pixel (x, y) (`picking.pixel_ray`, row 0 at
the top), from the near plane to the far plane, clipped to the volume's bounds. It is cut exactly
where it crosses from one voxel into the next (the planes half a spacing between grid points, as
Amanatides and Woo's voxel traversal), so no voxel it passes through is skipped however thin its
piece. The picked label is that of the first piece that is visible: its label is drawn (shown,
opacity scale above 0: `LabelTransferFunction.effective_tf`) and that label's TF gives the
trilinear value at the middle of the piece some opacity. None: the ray meets no visible label.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from volren.app.core.picking import pixel_ray, sample_grid
from volren.errors import VolrenError
from volren.kernels.box_clipping import clip_box
from volren.kernels.tet_projection import ray_far
from volren.model.camera import Camera
from volren.model.labels import LabelTransferFunction
from volren.model.volume import UniformVolume


@dataclass(frozen=True)
class LabelPick:
    """The label picked, where the ray enters its voxel (world units), and how far along the ray."""

    label: int
    position: tuple[float, float, float]
    depth: float


def voxel_pieces(volume: UniformVolume, origin: NDArray, direction: NDArray, t_far: float) -> NDArray | None:
    """(n + 1,) distances along the ray where it enters the volume's box, crosses from one voxel
    (nearest grid point) into the next, and leaves the box; None where it misses the box."""
    b = np.asarray(volume.bounds, dtype=np.float64)
    t0, t1 = clip_box(  # type: ignore[call-arg]  # a numba dispatcher
        *origin, *direction, np.ascontiguousarray(b[0::2]), np.ascontiguousarray(b[1::2]), 0.0, t_far
    )
    if not t1 > t0:
        return None
    spacing = np.asarray(volume.spacing, dtype=np.float64)
    start = (origin - np.asarray(volume.origin, dtype=np.float64)) / spacing  # index units at t = 0
    rate = direction / spacing
    cuts = [np.array([t0, t1])]
    for axis, n in enumerate(volume.dimensions):
        if rate[axis] == 0.0 or n < 2:
            continue
        planes = np.arange(n - 1) + 0.5  # between grid points k and k + 1
        t = (planes - start[axis]) / rate[axis]
        cuts.append(t[(t > t0) & (t < t1)])
    return np.unique(np.concatenate(cuts))


def pick_label(
    volume: UniformVolume,
    label_tf: LabelTransferFunction,
    camera: Camera,
    x: int,
    y: int,
    width: int,
    height: int,
) -> LabelPick | None:
    """The first visible label along the ray through pixel (x, y) of a width x height view (see the
    module docstring), or None."""
    if width < 1 or height < 1:
        raise VolrenError(f"picking needs an image of at least 1 x 1 pixels, got {width} x {height}")
    labels = getattr(volume, "labels", None)
    if labels is None or not (0 <= x < width and 0 <= y < height):
        return None
    origin, direction = pixel_ray(camera, x, y, width, height)
    t_far = float(ray_far(camera, direction[None, :])[0])
    cuts = voxel_pieces(volume, origin, direction, t_far)
    if cuts is None or len(cuts) < 2:
        return None
    middles = 0.5 * (cuts[:-1] + cuts[1:])
    points = origin + middles[:, None] * direction
    index = np.rint((points - np.asarray(volume.origin)) / np.asarray(volume.spacing)).astype(np.int64)
    index = np.clip(index, 0, np.asarray(volume.dimensions) - 1)
    found = labels.values[index[:, 2], index[:, 1], index[:, 0]].astype(np.int64)
    values, _ = sample_grid(volume, points)
    visible = np.zeros(len(found), dtype=bool)
    for label in np.unique(found):
        tf = label_tf.effective_tf(int(label))
        if tf is None:
            continue
        here = found == label
        _, alpha = tf.sample(values[here])
        visible[here] = np.isfinite(values[here]) & (alpha > 0.0)
    first = np.flatnonzero(visible)
    if first.size == 0:
        return None
    n = int(first[0])
    entry = origin + cuts[n] * direction
    return LabelPick(int(found[n]), (float(entry[0]), float(entry[1]), float(entry[2])), float(cuts[n]))
