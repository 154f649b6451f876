"""The part of a whole uniform volume that one brick's render draws (sort-last compositing).

Why: a volume too large for one texture, one process or one machine is cut into bricks; each
brick is rendered into a premultiplied RGBA layer, and the layers are composited front to back.
For the composite to equal the whole-volume render, every renderer drawing a brick must sample
each ray exactly where the whole render would, and draw exactly the part of it that the brick
owns. A `Region` tells it both:

- `owner_min`/`owner_max`: the brick's own box, half-open ([min, max) per axis, world units). A
  ray's piece (a sample, or a segment identified by a point of it) belongs to the brick whose box
  holds that point, so neighbouring bricks never both draw it nor both skip it. Faces on the
  whole volume's boundary are pushed out by a voxel, so points on them belong to a brick.
- `whole_bounds`: the whole volume's box. Rays enter it where the whole render's rays do, and
  samples are anchored to it (t0 + k * step along every ray, the same k for every brick).
- `value_range`: the whole volume's finite value range: normalisation and thresholds that
  depend on it must not change from brick to brick.

The renderer's volume is then the brick's sub-volume: its voxels plus `ghost` voxels beyond every
face that is not on the whole volume's boundary, so that interpolation and gradients near a face
read the neighbour's true values (`volren.bricked.layout` cuts them).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from volren.errors import VolrenError
from volren.model.camera import Camera

Triple = tuple[float, float, float]
Bounds = tuple[float, float, float, float, float, float]


@dataclass(frozen=True)
class Region:
    """A brick's share of the whole volume's render (see the module docstring)."""

    owner_min: Triple
    owner_max: Triple
    whole_bounds: Bounds
    value_range: tuple[float, float]

    def __post_init__(self) -> None:
        numbers = (*self.owner_min, *self.owner_max, *self.whole_bounds, *self.value_range)
        if len(self.owner_min) != 3 or len(self.owner_max) != 3 or len(self.whole_bounds) != 6:
            raise VolrenError("a region needs 3 owner_min, 3 owner_max and 6 whole_bounds numbers")
        if not all(np.isfinite(v) for v in numbers):
            raise VolrenError(f"a region's box and value range must be finite, got {self}")
        if not all(lo < hi for lo, hi in zip(self.owner_min, self.owner_max)):
            raise VolrenError(
                f"a region's owner box must have min < max per axis, got {self.owner_min}..{self.owner_max}"
            )
        if not self.value_range[0] <= self.value_range[1]:
            raise VolrenError(f"a region's value range must have lo <= hi, got {self.value_range}")

    @property
    def whole_min(self) -> Triple:
        return tuple(float(v) for v in self.whole_bounds[0::2])  # type: ignore[return-value]

    @property
    def whole_max(self) -> Triple:
        return tuple(float(v) for v in self.whole_bounds[1::2])  # type: ignore[return-value]

    @property
    def box(self) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi): the owner box within the whole box, the part of space this brick draws."""
        return np.maximum(self.owner_min, self.whole_min), np.minimum(self.owner_max, self.whole_max)

    def owns(self, points: np.ndarray) -> np.ndarray:
        """Which of the (..., 3) world points belong to this region (half-open box)."""
        points = np.asarray(points)
        return np.all((points >= self.owner_min) & (points < self.owner_max), axis=-1)

    def pixel_rect(self, camera: Camera, width: int, height: int) -> tuple[int, int, int, int]:
        """(x0, y0, x1, y1), row 0 at the top, end exclusive: the pixels whose rays can meet this
        region's box (the owner box within the whole box), a pixel wider on every side. The whole
        image when a corner lies behind the eye."""
        lo, hi = self.box
        corners = np.array(
            [[x, y, z, 1.0] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
        )
        clip = corners @ (camera.projection_matrix(width / height) @ camera.view_matrix()).T
        if np.any(clip[:, 3] <= 1e-9):
            return 0, 0, width, height
        ndc = clip[:, :2] / clip[:, 3:4]
        px = (ndc[:, 0] + 1.0) * 0.5 * width
        py = (1.0 - ndc[:, 1]) * 0.5 * height
        x0 = int(np.clip(np.floor(px.min()) - 1, 0, width))
        x1 = int(np.clip(np.ceil(px.max()) + 1, 0, width))
        y0 = int(np.clip(np.floor(py.min()) - 1, 0, height))
        y1 = int(np.clip(np.ceil(py.max()) + 1, 0, height))
        return x0, y0, max(x0, x1), max(y0, y1)
