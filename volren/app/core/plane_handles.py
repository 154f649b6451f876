"""A clip plane's handles in the viewport: its outline across the volume's box, a handle at its
centre that moves it along its normal, and one at the tip of its normal arrow that turns it (no Qt).

Why two handles: a plane has one position and two angles, and users of ParaView's plane widget
and Slicer's slice planes expect to push a plane through the data and to tilt it. Moving follows
the mouse's motion projected onto the normal's direction on screen, as the crop box's faces do
(`crop_handles`); turning rotates the normal about the camera's up and right axes by the mouse's
motion (a half turn across the view, as the trackball turns the camera), about the handle's
centre. With Shift the turned normal snaps to the nearest axis (its sign kept).

A drag is measured from where it started, so dragging past a limit and back brings the plane
back under the mouse; a moved plane stays within the box's extent along its normal.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from volren.app.core.crop_handles import PICK_RADIUS, cursor_kind
from volren.app.core.overlay_geometry import Rect, project_points
from volren.model.camera import Camera
from volren.model.clip_region import ClipPlane

HandleKind = Literal["move", "turn"]
#: The normal arrow's length: this share of the box's diagonal.
ARROW_SHARE = 0.2
#: The step along the normal whose projection gives the pixels per unit, as a share of the
#: camera's distance to the handle (see `crop_handles.AXIS_STEP_SHARE`).
STEP_SHARE = 1e-3

_CORNER_BITS = np.array([[(i >> a) & 1 for a in range(3)] for i in range(8)], dtype=np.float64)
_EDGES = [(i, i | (1 << a)) for a in range(3) for i in range(8) if not i & (1 << a)]


def _unit(vector: Sequence[float]) -> NDArray[np.float64]:
    v = np.asarray(vector, dtype=np.float64)
    return v / np.linalg.norm(v)


def plane_polygon(plane: ClipPlane, bounds: Sequence[float]) -> NDArray[np.float64]:
    """Where the plane cuts the box `bounds`: (k, 3) corners in order around the polygon, k = 3..6,
    or (0, 3) where it misses the box."""
    lo, hi = np.asarray(bounds[0::2], dtype=np.float64), np.asarray(bounds[1::2], dtype=np.float64)
    corners = lo + _CORNER_BITS * (hi - lo)
    n = _unit(plane.normal)
    side = (corners - np.asarray(plane.origin)) @ n
    points = []
    for i, j in _EDGES:
        if (side[i] < 0.0) != (side[j] < 0.0) or side[i] == 0.0:
            t = side[i] / (side[i] - side[j]) if side[i] != side[j] else 0.0
            points.append(corners[i] + t * (corners[j] - corners[i]))
    if len(points) < 3:
        return np.zeros((0, 3))
    pts = np.unique(np.round(np.asarray(points), 12), axis=0)
    centre = pts.mean(axis=0)
    u = _unit(np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0]))
    v = np.cross(n, u)
    angles = np.arctan2((pts - centre) @ v, (pts - centre) @ u)
    return pts[np.argsort(angles)]


def handle_points(plane: ClipPlane, bounds: Sequence[float]) -> NDArray[np.float64]:
    """The move handle (the centre of the plane's polygon, else its point) and the turn handle (the
    tip of an arrow along the kept side's normal), (2, 3) world points."""
    polygon = plane_polygon(plane, bounds)
    centre = polygon.mean(axis=0) if len(polygon) else np.asarray(plane.origin, dtype=np.float64)
    diagonal = float(np.linalg.norm(np.subtract(bounds[1::2], bounds[0::2])))
    kept = np.asarray(plane.half_space()[:3])
    return np.stack([centre, centre + ARROW_SHARE * diagonal * kept])


def handle_at(camera: Camera, aspect: float, rect: Rect, plane: ClipPlane, bounds: Sequence[float], x: float,
              y: float, radius: float = PICK_RADIUS) -> HandleKind | None:  # fmt: skip
    """The handle within `radius` pixels of (x, y), the closer one; None when there is none."""
    pixels = project_points(camera, aspect, rect, handle_points(plane, bounds))
    best: tuple[float, HandleKind] | None = None
    for kind, (px, py) in zip(("move", "turn"), pixels, strict=True):
        if math.isfinite(px) and math.isfinite(py):
            distance = math.hypot(px - x, py - y)
            if distance <= radius and (best is None or distance < best[0]):
                best = (distance, kind)  # type: ignore[assignment]
    return None if best is None else best[1]


def extent_along(bounds: Sequence[float], normal: Sequence[float]) -> tuple[float, float]:
    """The least and greatest n . x over the corners of `bounds`, n the unit normal."""
    lo, hi = np.asarray(bounds[0::2], dtype=np.float64), np.asarray(bounds[1::2], dtype=np.float64)
    along = (lo + _CORNER_BITS * (hi - lo)) @ _unit(normal)
    return float(along.min()), float(along.max())


def snapped(normal: Sequence[float]) -> tuple[float, float, float]:
    """The axis nearest to `normal`, with its sign."""
    n = _unit(normal)
    axis = int(np.argmax(np.abs(n)))
    out = [0.0, 0.0, 0.0]
    out[axis] = 1.0 if n[axis] > 0 else -1.0
    return out[0], out[1], out[2]


def _rotation(axis: NDArray[np.float64], angle: float) -> NDArray[np.float64]:
    """Rodrigues' rotation matrix about the unit `axis`."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * (k @ k)


@dataclass(frozen=True)
class PlaneDrag:
    """One drag of one of a plane's handles: the plane at the press and how the view shows it."""

    kind: HandleKind
    start: ClipPlane
    centre: tuple[float, float, float]
    #: move: the screen vector (pixels, y down) of one world unit along the unit normal
    normal_pixels: tuple[float, float]
    #: turn: the camera's right and up axes (world) and the radians per pixel
    right: tuple[float, float, float]
    up: tuple[float, float, float]
    radians_per_pixel: float
    bounds: tuple[float, ...]

    @classmethod
    def start_at(cls, kind: HandleKind, camera: Camera, aspect: float, rect: Rect, plane: ClipPlane,
                 bounds: Sequence[float]) -> PlaneDrag | None:  # fmt: skip
        """The drag of `kind`, or None where the handle lies behind the camera, or a move when the
        normal is seen end-on (no screen direction to follow)."""
        centre = handle_points(plane, bounds)[0]
        n = _unit(plane.normal)
        step = STEP_SHARE * max(float(np.linalg.norm(centre - np.asarray(camera.position))), 1e-12)
        pixels = project_points(camera, aspect, rect, np.stack([centre, centre + step * n]))
        if not np.all(np.isfinite(pixels)):
            return None
        vector = (pixels[1] - pixels[0]) / step
        if kind == "move" and not float(np.hypot(*vector)) > 1e-3:
            return None
        view = _unit(camera.direction)
        up = _unit(camera.view_up)
        right = _unit(np.cross(view, up))
        up = np.cross(right, view)
        return cls(kind, plane, tuple(float(v) for v in centre), (float(vector[0]), float(vector[1])),  # type: ignore[arg-type]
                   tuple(float(v) for v in right), tuple(float(v) for v in up),  # type: ignore[arg-type]
                   math.pi / max(min(rect[2], rect[3]), 1.0), tuple(float(v) for v in bounds))  # fmt: skip

    def plane_for(self, dx: float, dy: float, snap: bool = False) -> ClipPlane:
        """The plane after the mouse moved (dx, dy) pixels since the press (Shift: `snap`)."""
        p = self.start
        if self.kind == "move":
            ax, ay = self.normal_pixels
            distance = (dx * ax + dy * ay) / (ax * ax + ay * ay)
            n = _unit(p.normal)
            lo, hi = extent_along(self.bounds, p.normal)
            at = float(np.asarray(p.origin) @ n)
            target = min(max(at + distance, lo), hi)
            return ClipPlane(tuple(np.asarray(p.origin) + (target - at) * n), p.normal, p.invert, p.enabled)  # type: ignore[arg-type]
        turn = _rotation(np.asarray(self.up), dx * self.radians_per_pixel) @ _rotation(
            np.asarray(self.right), dy * self.radians_per_pixel
        )
        normal = turn @ _unit(p.normal)
        if snap:
            normal = np.asarray(snapped(normal))
        return ClipPlane(self.centre, tuple(float(v) for v in normal), p.invert, p.enabled)  # type: ignore[arg-type]

    def cursor(self) -> str:
        """The size cursor along the normal on screen (`crop_handles.cursor_kind`) for a move; a
        turn uses the closed hand."""
        return cursor_kind(self.normal_pixels) if self.kind == "move" else "turn"
