"""The camera, with VTK's conventions so that every renderer draws the same pixels.

`Camera` mirrors vtkCamera: a position, a focal point, a view-up vector, a vertical view angle
(perspective) or a parallel scale (parallel projection), and a clipping range. `reset` fits the
bounding sphere of the data exactly as vtkRenderer.ResetCamera does, `azimuth`, `elevation` and
`zoom` act as vtkCamera's methods of the same names, and `view_matrix` / `projection_matrix`
equal vtkCamera.GetViewTransformMatrix() / GetProjectionTransformMatrix(aspect, -1, 1).

DESIGN.md's convention for a scene is `Camera.orbit(bounds, azimuth, elevation, zoom)`: the VTK
default camera (at +z looking toward -z, +y up), reset on the bounds, then azimuth, elevation and
zoom in that order. Cameras are immutable: every operation returns a new camera.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from volren.errors import VolrenError

Vec3 = tuple[float, float, float]

#: vtkRenderer's ClippingRangeExpansion default.
CLIPPING_RANGE_EXPANSION = 0.5
#: vtkRenderer's NearClippingPlaneTolerance for a depth buffer of more than 16 bits.
NEAR_CLIPPING_PLANE_TOLERANCE = 0.001
#: Zoom factors (one call of `Camera.zoom`, or a scene's zoom) beyond these are typos, not views:
#: the data shrinks a million times below its fitted size or a voxel fills the image a million
#: times over, and VTK's float32 projection loses the data altogether (blank images at 1e300).
MIN_ZOOM = 1e-6
MAX_ZOOM = 1e6
#: Camera positions and focal points beyond this in any coordinate are typos (1e200), not places:
#: the renderers work in float32, where the square of a distance overflows beyond 1.8e19.
MAX_COORDINATE = 1e18
#: The fields of a camera dict that are lists of numbers, and their lengths.
_VECTOR_FIELDS = {"position": 3, "focal_point": 3, "view_up": 3, "clipping_range": 2}


def check_zoom(zoom: float, parallel: bool, view_angle: float = 30.0, name: str = "camera zoom") -> None:
    """Refuse a zoom that draws nothing sensible: outside [MIN_ZOOM, MAX_ZOOM], or (in perspective)
    one that would widen `view_angle` to 180 degrees or more. `name` is what the caller calls it."""
    try:
        value = float(zoom)
    except (TypeError, ValueError):
        value = math.nan
    if not MIN_ZOOM <= value <= MAX_ZOOM:  # False for NaN
        raise VolrenError(f"{name} must lie in [{MIN_ZOOM:g}, {MAX_ZOOM:g}], got {zoom!r}")
    if not parallel and view_angle / value >= 180.0:
        raise VolrenError(
            f"{name} {value:g} would widen the {view_angle:g} degree view angle to {view_angle / value:.4g}; "
            f"a perspective view needs a zoom above {view_angle / 180.0:.4g} (or a parallel projection)"
        )


def _vec(value: Sequence[float], what: str) -> Vec3:
    arr = np.asarray(value, dtype=np.float64).reshape(-1)
    if arr.size != 3 or not np.all(np.isfinite(arr)):
        raise VolrenError(f"camera {what} must be three finite numbers, got {value!r}")
    return (float(arr[0]), float(arr[1]), float(arr[2]))


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float | np.integer | np.floating) and not isinstance(value, bool)


def _field_from_json(key: str, value: Any) -> Any:
    """One field of a camera dict, checked for its type: numbers where numbers belong (float()
    would take the string "1e2" and the boolean true without a word)."""
    if key == "parallel":
        if not isinstance(value, bool):
            raise VolrenError(f"camera parallel must be true or false, got {value!r}")
        return value
    count = _VECTOR_FIELDS.get(key)
    items = value if count else [value]
    if not isinstance(items, list | tuple) or len(items) != (count or 1) or not all(map(_is_number, items)):
        raise VolrenError(f"camera {key.replace('_', ' ')} must be {f'{count} numbers' if count else 'a number'}, "
                          f"got {value!r}")  # fmt: skip
    try:
        return tuple(float(v) for v in items) if count else float(value)
    except OverflowError:  # an integer beyond float64
        raise VolrenError(f"camera {key.replace('_', ' ')} must be finite") from None


def _normalized(v: NDArray) -> NDArray:
    n = np.linalg.norm(v)
    return v / n if n > 0 else v


def _cross3(a: Sequence[float] | NDArray[np.float64], b: Sequence[float] | NDArray[np.float64]) -> Vec3:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _unit3(v: Vec3) -> Vec3:
    """v / |v| (v itself when it is zero, as `_normalized`)."""
    n = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    return (v[0] / n, v[1] / n, v[2] / n) if n > 0 else v


def rotation_matrix(angle_deg: float, axis: ArrayLike) -> NDArray[np.float64]:
    """3x3 rotation by `angle_deg` about `axis` (right-hand rule), as vtkTransform.RotateWXYZ."""
    x, y, z = _normalized(np.asarray(axis, dtype=np.float64))
    a = math.radians(angle_deg)
    c, s = math.cos(a), math.sin(a)
    t = 1.0 - c
    return np.array(
        [
            [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
            [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
            [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
        ]
    )


def bounds_corners(bounds: Sequence[float]) -> NDArray[np.float64]:
    """The 8 corners of (xmin, xmax, ymin, ymax, zmin, zmax), x varying fastest."""
    b = [float(v) for v in bounds]
    return np.array([[b[i], b[2 + j], b[4 + k]] for k in (0, 1) for j in (0, 1) for i in (0, 1)])


@dataclass(frozen=True)
class Camera:
    """A vtkCamera-like pinhole or parallel camera (all lengths in world units)."""

    position: Vec3 = (0.0, 0.0, 1.0)
    focal_point: Vec3 = (0.0, 0.0, 0.0)
    view_up: Vec3 = (0.0, 1.0, 0.0)
    view_angle: float = 30.0
    parallel: bool = False
    parallel_scale: float = 1.0
    clipping_range: tuple[float, float] = (0.01, 1000.01)

    def __post_init__(self) -> None:
        object.__setattr__(self, "position", _vec(self.position, "position"))
        object.__setattr__(self, "focal_point", _vec(self.focal_point, "focal point"))
        object.__setattr__(self, "view_up", _vec(self.view_up, "view up"))
        for what, point in (("position", self.position), ("focal point", self.focal_point)):
            if max(map(abs, point)) > MAX_COORDINATE:
                raise VolrenError(
                    f"camera {what} {list(point)} lies beyond {MAX_COORDINATE:g} from the origin"
                )
        if self.view_up == (0.0, 0.0, 0.0):
            raise VolrenError("camera view up is the zero vector; give the direction that is up in the image")
        if np.allclose(self.position, self.focal_point):
            raise VolrenError("camera position and focal point coincide")
        if not (0.0 < self.view_angle < 180.0):
            raise VolrenError(f"camera view angle must lie in (0, 180) degrees, got {self.view_angle}")
        if not (self.parallel_scale > 0 and math.isfinite(self.parallel_scale)):
            raise VolrenError(f"camera parallel scale must be positive, got {self.parallel_scale}")
        near, far = (float(v) for v in self.clipping_range)
        if not (0 < near < far and math.isfinite(far)):
            raise VolrenError(f"camera clipping range must satisfy 0 < near < far, got {self.clipping_range}")
        object.__setattr__(self, "clipping_range", (near, far))

    # -------------------------------------------------------------------------- geometry
    @property
    def distance(self) -> float:
        return float(np.linalg.norm(np.subtract(self.position, self.focal_point)))

    @property
    def direction(self) -> NDArray[np.float64]:
        """Unit direction of projection (from the position toward the focal point)."""
        return _normalized(np.subtract(self.focal_point, self.position))

    def depth_range(self, bounds: Sequence[float]) -> tuple[float, float]:
        """The nearest and farthest depth of the box `bounds`' corners along the view direction,
        from the eye: where the near and far planes cut the box when they lie between the two."""
        depth = (bounds_corners(bounds) - np.asarray(self.position, dtype=np.float64)) @ self.direction
        return float(depth.min()), float(depth.max())

    def _axes(self) -> tuple[NDArray, NDArray, NDArray]:
        """(sideways, orthogonal up, view-plane normal): the rows of the view rotation. In plain
        floats: numpy's cross product of two 3-vectors costs ~80 us, and renderers ask for the view
        matrix every frame (it was 0.2 ms of a 10 ms shear-warp frame)."""
        vpn = _unit3(cast(Vec3, tuple(p - f for p, f in zip(self.position, self.focal_point, strict=True))))
        side = _unit3(_cross3(self.view_up, vpn))
        up = _cross3(vpn, side)
        return np.array(side), np.array(up), np.array(vpn)

    def view_matrix(self) -> NDArray[np.float64]:
        """World to eye coordinates (vtkCamera.GetViewTransformMatrix)."""
        side, up, vpn = self._axes()
        m = np.eye(4)
        m[0, :3], m[1, :3], m[2, :3] = side, up, vpn
        m[:3, 3] = -m[:3, :3] @ np.asarray(self.position)
        return m

    def projection_matrix(self, aspect: float) -> NDArray[np.float64]:
        """Eye to clip coordinates, OpenGL's [-1, 1] depth (GetProjectionTransformMatrix(aspect, -1, 1))."""
        near, far = self.clipping_range
        m = np.zeros((4, 4))
        if self.parallel:
            height = self.parallel_scale
            width = height * aspect
            m[0, 0] = 1.0 / width
            m[1, 1] = 1.0 / height
            m[2, 2] = -2.0 / (far - near)
            m[2, 3] = -(far + near) / (far - near)
            m[3, 3] = 1.0
        else:
            tmp = math.tan(math.radians(self.view_angle) / 2.0)
            height = near * tmp
            width = height * aspect
            m[0, 0] = near / width
            m[1, 1] = near / height
            m[2, 2] = -(far + near) / (far - near)
            m[2, 3] = -2.0 * far * near / (far - near)
            m[3, 2] = -1.0
        return m

    def pixel_rays(self, width: int, height: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Origins and unit directions (H, W, 3) of the rays through pixel centres, row 0 at the top.

        Origins lie on the near clipping plane, as in a GPU ray caster.
        """
        xx, yy = np.meshgrid(np.arange(width), np.arange(height))
        return self.rays(width, height, xx, yy)

    def rays(
        self, width: int, height: int, x: ArrayLike, y: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Origins and unit directions (..., 3) of the rays through the centres of pixels (x, y) of a
        width x height image: `pixel_rays` at those pixels (to rounding; picking asks for one pixel).
        x and y broadcast. Renderers that need many rays per frame use `volren.kernels.camera_rays`."""
        inv = np.linalg.inv(self.projection_matrix(width / height) @ self.view_matrix())
        xx, yy = np.broadcast_arrays(
            (np.asarray(x, dtype=np.float64) + 0.5) / width * 2.0 - 1.0,
            1.0 - (np.asarray(y, dtype=np.float64) + 0.5) / height * 2.0,
        )
        ones = np.ones_like(xx)

        def unproject(z: float) -> NDArray:
            clip = np.stack([xx, yy, z * ones, ones], axis=-1) @ inv.T
            return clip[..., :3] / clip[..., 3:4]

        near, far = unproject(-1.0), unproject(1.0)
        directions = far - near
        directions /= np.linalg.norm(directions, axis=-1, keepdims=True)
        return near, directions

    # ------------------------------------------------------------------------ operations
    def reset(self, bounds: Sequence[float], aspect: float = 1.0) -> Camera:
        """Fit the bounding sphere of `bounds`, keeping the view direction (vtkRenderer.ResetCamera)."""
        b = np.asarray(bounds, dtype=np.float64)
        if b.shape != (6,) or not np.all(np.isfinite(b)) or np.any(b[1::2] < b[0::2]):
            raise VolrenError(f"cannot reset the camera on bounds {tuple(bounds)}")
        center = (b[0::2] + b[1::2]) / 2.0
        w = b[1::2] - b[0::2]
        radius = float(np.sum(w * w))
        radius = math.sqrt(radius if radius != 0 else 1.0) * 0.5
        angle = math.radians(self.view_angle)
        parallel_scale = radius
        if aspect < 1.0:
            angle = 2.0 * math.atan(math.tan(angle * 0.5) * aspect)
            parallel_scale = radius / aspect
        distance = radius / math.sin(angle * 0.5)
        vpn = _normalized(np.subtract(self.position, self.focal_point))
        view_up = np.asarray(self.view_up)
        if abs(float(np.dot(view_up, vpn))) > 0.999:
            view_up = np.array([-view_up[2], view_up[0], view_up[1]])
        cam = replace(
            self,
            focal_point=tuple(center),
            position=tuple(center + distance * vpn),
            view_up=tuple(view_up),
            parallel_scale=parallel_scale,
        )
        return cam.reset_clipping_range(bounds)

    def reset_clipping_range(self, bounds: Sequence[float]) -> Camera:
        """Near and far planes that enclose `bounds` (vtkRenderer.ResetCameraClippingRange)."""
        _, _, vpn = self._axes()
        a, bb, c = -vpn
        pos = np.asarray(self.position)
        d = -(a * pos[0] + bb * pos[1] + c * pos[2])
        dist = bounds_corners(bounds) @ np.array([a, bb, c]) + d
        lo = min(float(dist.min()), float(dist[0]))
        hi = max(float(dist.max()), 1e-18)
        if self.parallel:
            min_gap = 0.1 * self.parallel_scale
        else:
            min_gap = 0.2 * math.tan(math.radians(self.view_angle) / 2.0) * hi
        if hi - lo < min_gap:
            min_gap = min_gap - hi + lo
            hi += min_gap / 2.0
            lo -= min_gap / 2.0
        lo = max(lo, 0.0)
        lo = 0.99 * lo - (hi - lo) * CLIPPING_RANGE_EXPANSION
        hi = 1.01 * hi + (hi - lo) * CLIPPING_RANGE_EXPANSION  # uses the new near, as VTK does
        if lo >= hi:
            lo = 0.01 * hi
        lo = max(lo, NEAR_CLIPPING_PLANE_TOLERANCE * hi)
        return replace(self, clipping_range=(lo, hi))

    def azimuth(self, degrees: float) -> Camera:
        """Rotate the position about the view-up vector through the focal point."""
        fp = np.asarray(self.focal_point)
        rot = rotation_matrix(degrees, self.view_up)
        return replace(self, position=tuple(fp + rot @ (np.asarray(self.position) - fp)))

    def elevation(self, degrees: float) -> Camera:
        """Rotate the position about the sideways axis through the focal point.

        Like vtkCamera.Elevation, the view matrix afterwards uses the rotated view-up, which is
        what we store, so elevations of +-90 degrees stay well defined.
        """
        side, _, _ = self._axes()
        rot = rotation_matrix(degrees, -side)
        fp = np.asarray(self.focal_point)
        return replace(
            self,
            position=tuple(fp + rot @ (np.asarray(self.position) - fp)),
            view_up=tuple(rot @ np.asarray(self.view_up)),
        )

    def roll(self, degrees: float) -> Camera:
        """Rotate the view-up vector about the direction of projection."""
        rot = rotation_matrix(degrees, self.direction)
        return replace(self, view_up=tuple(rot @ np.asarray(self.view_up)))

    def zoom(self, factor: float) -> Camera:
        """Narrow the view angle (or parallel scale) by `factor` (> 1 enlarges the image)."""
        check_zoom(factor, self.parallel, self.view_angle, "zoom factor")
        if self.parallel:
            return replace(self, parallel_scale=self.parallel_scale / factor)
        return replace(self, view_angle=self.view_angle / factor)

    def dolly(self, factor: float) -> Camera:
        """Move the position toward the focal point, dividing the distance by `factor`."""
        if not (factor > 0 and math.isfinite(factor)):
            raise VolrenError(f"dolly factor must be positive, got {factor}")
        fp = np.asarray(self.focal_point)
        return replace(self, position=tuple(fp + (np.asarray(self.position) - fp) / factor))

    def pan(self, dx: float, dy: float) -> Camera:
        """Move position and focal point by (dx, dy) world units along the screen axes."""
        side, up, _ = self._axes()
        shift = dx * side + dy * up
        return replace(
            self,
            position=tuple(np.asarray(self.position) + shift),
            focal_point=tuple(np.asarray(self.focal_point) + shift),
        )

    def orthogonalize_view_up(self) -> Camera:
        _, up, _ = self._axes()
        return replace(self, view_up=tuple(up))

    @classmethod
    def orbit(
        cls,
        bounds: Sequence[float],
        azimuth: float = 0.0,
        elevation: float = 0.0,
        zoom: float = 1.0,
        parallel: bool = False,
        aspect: float = 1.0,
    ) -> Camera:
        """DESIGN.md's scene camera: default camera, reset on `bounds`, azimuth, elevation, zoom.

        The clipping range is reset on the bounds at the end so the near plane lies before the data.
        """
        cam = cls(parallel=parallel).reset(bounds, aspect)
        cam = cam.azimuth(azimuth).elevation(elevation).zoom(zoom)
        return cam.reset_clipping_range(bounds)

    # --------------------------------------------------------------------------- files
    def to_dict(self) -> dict[str, Any]:
        return {
            "position": list(self.position),
            "focal_point": list(self.focal_point),
            "view_up": list(self.view_up),
            "view_angle": self.view_angle,
            "parallel": self.parallel,
            "parallel_scale": self.parallel_scale,
            "clipping_range": list(self.clipping_range),
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Camera:
        known = {f for f in cls.__dataclass_fields__}
        unknown = set(data) - known
        if unknown:
            raise VolrenError(f"unknown camera keys {sorted(unknown)}; expected some of {sorted(known)}")
        camera = cls(**{key: _field_from_json(key, value) for key, value in data.items()})
        if math.hypot(*_cross3(_unit3(camera.view_up), camera.direction)) < 1e-9:
            raise VolrenError(
                f"camera view up {list(camera.view_up)} is along the view direction, so no direction in the "
                "image is up; give one across it"
            )
        return camera
