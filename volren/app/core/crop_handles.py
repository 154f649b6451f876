"""The crop box's face handles in the viewport: where they fall, which one a pixel hits, and the
box a drag makes (no Qt).

Why faces and not corners: cropping is axis-aligned, so each face is one number of the box and
dragging it changes that number only, as ParaView's box widget and Slicer's ROI do. A face moves
along its axis by the mouse motion projected onto the axis's direction on screen: the handle's
centre and a point a small step along the axis are projected (`overlay_geometry`, the renderers'
own matrices at the frame's aspect), their screen vector gives pixels per world unit, and the
world displacement is dot(mouse delta, screen axis unit) / pixels per unit. A face seen end-on
(its axis nearly along the ray through its handle) has no usable screen direction, so it is not
offered: pressing there rotates the camera as anywhere else.

A drag is measured from where it started (the box at the press and the total mouse delta), so
dragging past a limit and back brings the face back under the mouse. The face stays within the
volume's bounds and at least `minimum_thickness` from the opposite face (one voxel on a grid, a
share of the extent on a mesh); the opposite face never moves.

Faces are numbered as the six numbers of a `Box`: 0 xmin, 1 xmax, 2 ymin, 3 ymax, 4 zmin, 5 zmax.
Rectangles are (x, y, width, height) in widget pixels, as in `overlay_geometry`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from volren.app.core.overlay_geometry import Rect, project_points
from volren.model.camera import Camera
from volren.model.crop import Box
from volren.model.volume import Volume

#: The faces in `Box` order: the side of the box each number of a `Box` is.
FACE_NAMES = ("-X", "+X", "-Y", "+Y", "-Z", "+Z")
#: A press this close to a handle's centre (widget pixels) grabs it: a few pixels beyond its drawing.
PICK_RADIUS = 8.0
#: A face whose axis lies within this angle of the ray through its handle is seen end-on: not offered.
MIN_AXIS_ANGLE_DEG = 10.0
#: On a mesh (no voxels) the box stays at least this share of the volume's extent thick.
MESH_MIN_THICKNESS_SHARE = 0.01
#: The step along the axis whose projection gives the pixels per unit, as a share of the camera's
#: distance to the handle: small enough to be the local rate, large enough to be far from rounding.
AXIS_STEP_SHARE = 1e-3

CursorKind = Literal["horizontal", "vertical", "rising", "falling"]


def face_axis(face: int) -> int:
    """The axis (0 x, 1 y, 2 z) a face moves along."""
    return face // 2


def shown_box(crop: Sequence[float] | None, bounds: Sequence[float]) -> Box:
    """The box the handles show: the crop box cut to the volume's bounds, or the bounds when there
    is no crop (a scene's box may reach past the volume; only the part inside crops anything)."""
    b = [float(v) for v in bounds]
    if crop is None:
        return tuple(b)  # type: ignore[return-value]
    clipped = (min(max(float(v), b[i - i % 2]), b[i - i % 2 + 1]) for i, v in enumerate(crop))
    return tuple(clipped)  # type: ignore[return-value]


def face_centres(box: Sequence[float]) -> NDArray[np.float64]:
    """The centres (6, 3) of the box's faces, in `Box` order."""
    b = np.asarray(box, dtype=np.float64)
    middle = (b[0::2] + b[1::2]) / 2.0
    centres = np.tile(middle, (6, 1))
    for face in range(6):
        centres[face, face_axis(face)] = b[face]
    return centres


def handle_pixels(camera: Camera, aspect: float, rect: Rect, box: Sequence[float]) -> NDArray[np.float64]:
    """Where the six handles fall on screen (6, 2); NaN for a face centre behind the near plane."""
    return project_points(camera, aspect, rect, face_centres(box))


def handle_depths(camera: Camera, box: Sequence[float]) -> NDArray[np.float64]:
    """How far in front of the camera each face centre lies (along the view direction): to draw the
    far handles first and to prefer the nearer of two handles on the same pixel."""
    return (face_centres(box) - np.asarray(camera.position)) @ camera.direction


def seen_end_on(camera: Camera, box: Sequence[float], face: int) -> bool:
    """Whether the face's axis lies within MIN_AXIS_ANGLE_DEG of the ray through its centre."""
    centre = face_centres(box)[face]
    ray = camera.direction if camera.parallel else centre - np.asarray(camera.position)
    norm = float(np.linalg.norm(ray))
    if norm == 0.0:
        return True
    cos = abs(float(ray[face_axis(face)])) / norm
    return cos >= math.cos(math.radians(MIN_AXIS_ANGLE_DEG))


def handle_at(
    camera: Camera,
    aspect: float,
    rect: Rect,
    box: Sequence[float],
    x: float,
    y: float,
    radius: float = PICK_RADIUS,
) -> int | None:
    """The face whose handle is within `radius` pixels of (x, y), the closest one (the nearer to the
    viewer on a tie), leaving out faces seen end-on; None when there is none."""
    pixels = handle_pixels(camera, aspect, rect, box)
    depths = handle_depths(camera, box)
    best: tuple[float, float, int] | None = None
    for face in range(6):
        px, py = pixels[face]
        if not (math.isfinite(px) and math.isfinite(py)) or seen_end_on(camera, box, face):
            continue
        distance = math.hypot(px - x, py - y)
        if distance <= radius and (best is None or (distance, depths[face]) < best[:2]):
            best = (distance, float(depths[face]), face)
    return None if best is None else best[2]


def minimum_thickness(volume: Volume) -> tuple[float, float, float]:
    """How thin the box may get along each axis: one sample spacing on a grid (cropping keeps two
    samples), a share of the extent on a mesh; never more than the extent itself."""
    b = volume.bounds
    extents = [float(b[2 * a + 1] - b[2 * a]) for a in range(3)]
    if volume.kind == "uniform":
        steps = [float(s) for s in volume.spacing]  # type: ignore[attr-defined]
    else:
        steps = [MESH_MIN_THICKNESS_SHARE * e for e in extents]
    return (min(steps[0], extents[0]), min(steps[1], extents[1]), min(steps[2], extents[2]))


def moved_face(box: Sequence[float], face: int, value: float, limits: Sequence[float],
               thickness: Sequence[float]) -> Box:  # fmt: skip
    """`box` with face `face` at `value`, kept within `limits` (the volume's bounds) and at least
    `thickness[axis]` from the opposite face; a box already thinner than that is not made thicker."""
    b = [float(v) for v in box]
    axis, start = face_axis(face), b[face]
    lo_limit, hi_limit = float(limits[2 * axis]), float(limits[2 * axis + 1])
    if face % 2:  # a max face: above the min face by the thickness, below the upper bound
        lowest = min(b[face - 1] + float(thickness[axis]), start)
        b[face] = min(max(value, lowest), max(hi_limit, start))
    else:
        highest = max(b[face + 1] - float(thickness[axis]), start)
        b[face] = max(min(value, highest), min(lo_limit, start))
    return tuple(b)  # type: ignore[return-value]


@dataclass(frozen=True)
class FaceDrag:
    """One drag of one face: the box at the press and how the face's axis lies on screen."""

    face: int
    start_box: Box
    #: The screen vector (pixels, y down) of one world unit along the face's axis (+x, +y or +z).
    axis_pixels: tuple[float, float]
    limits: Box
    thickness: tuple[float, float, float]

    @classmethod
    def start(cls, camera: Camera, aspect: float, rect: Rect, box: Sequence[float], face: int,
              limits: Sequence[float], thickness: Sequence[float]) -> FaceDrag | None:  # fmt: skip
        """The drag of `face` as the camera shows it, or None when the face is seen end-on or its
        handle lies behind the camera."""
        if seen_end_on(camera, box, face):
            return None
        centre = face_centres(box)[face]
        step = AXIS_STEP_SHARE * max(float(np.linalg.norm(centre - np.asarray(camera.position))), 1e-12)
        ahead = centre.copy()
        ahead[face_axis(face)] += step
        pixels = project_points(camera, aspect, rect, np.stack([centre, ahead]))
        if not np.all(np.isfinite(pixels)):
            return None
        vector = (pixels[1] - pixels[0]) / step
        if not float(np.hypot(*vector)) > 0.0:
            return None
        start_box: Box = tuple(float(v) for v in box)  # type: ignore[assignment]
        bounds: Box = tuple(float(v) for v in limits)  # type: ignore[assignment]
        thick = (float(thickness[0]), float(thickness[1]), float(thickness[2]))
        return cls(face, start_box, (float(vector[0]), float(vector[1])), bounds, thick)

    def distance(self, dx: float, dy: float) -> float:
        """World units along the face's axis for a mouse motion (dx, dy): the motion's component
        along the axis's screen direction, divided by the pixels per unit."""
        ax, ay = self.axis_pixels
        return (dx * ax + dy * ay) / (ax * ax + ay * ay)

    def box_for(self, dx: float, dy: float) -> Box:
        """The box after the mouse moved (dx, dy) pixels since the press."""
        value = self.start_box[self.face] + self.distance(dx, dy)
        return moved_face(self.start_box, self.face, value, self.limits, self.thickness)

    def cursor_kind(self) -> CursorKind:
        return cursor_kind(self.axis_pixels)


def cursor_kind(axis_pixels: Sequence[float]) -> CursorKind:
    """Which size cursor points along a screen direction (y down): horizontal, vertical, rising
    (lower left to upper right) or falling (upper left to lower right), to the nearest 45 degrees."""
    angle = math.degrees(math.atan2(-float(axis_pixels[1]), float(axis_pixels[0]))) % 180.0
    kinds: tuple[CursorKind, ...] = ("horizontal", "rising", "vertical", "falling", "horizontal")
    return kinds[int((angle + 22.5) // 45.0)]
