"""Volume clipping: the region of space a render keeps, cut by oblique planes and a crop box.

Why analytic clipping instead of a cut volume: a plane through a grid cuts cells, so a cropped or
masked volume shows a voxel staircase where the cut should be flat, and a mesh cut by whole cells
shows a jagged edge. Clipping each ray to the kept region instead (entry and exit parameters from
the planes) gives an exact cut surface on every volume kind and costs nothing per sample; moving a
plane or the box changes two numbers per ray, not the data a renderer prepared (Real-Time Volume
Graphics, chapter 15: clip planes on the ray's parameter interval).

The kept region is convex: the intersection of up to `MAX_PLANES` half-spaces and the crop box.
A plane keeps the side its normal points to, as `vtkPlane` does in VTK's volume mappers; `invert`
keeps the other side. Points on a plane are kept.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError

#: Most oblique planes in one region: VTK's volume mappers take six, and six planes already bound
#: any convex region a person edits by hand.
MAX_PLANES = 6

Triple = tuple[float, float, float]

#: (xmin, xmax, ymin, ymax, zmin, zmax) in world units, VTK's order.
Box = tuple[float, float, float, float, float, float]


def check_box(box: Sequence[float]) -> Box:
    """`box` as six finite floats with min <= max per axis, or a one-line VolrenError."""
    try:
        values = tuple(float(v) for v in box)
    except (TypeError, ValueError):
        raise VolrenError(
            f"a crop box is six numbers (xmin, xmax, ymin, ymax, zmin, zmax), got {box!r}"
        ) from None
    if len(values) != 6 or not all(math.isfinite(v) for v in values):
        raise VolrenError(
            f"a crop box is six finite numbers (xmin, xmax, ymin, ymax, zmin, zmax), got {box!r}"
        )
    for axis in range(3):
        if values[2 * axis] > values[2 * axis + 1]:
            raise VolrenError(
                f"crop box: {'xyz'[axis]}min {values[2 * axis]:g} is above {'xyz'[axis]}max "
                f"{values[2 * axis + 1]:g}"
            )
    return values  # type: ignore[return-value]


def _triple(values: Any, what: str) -> Triple:
    """`values` as three finite floats, or a one-line VolrenError naming `what`."""
    try:
        numbers = tuple(float(v) for v in values)
    except (TypeError, ValueError):
        raise VolrenError(f"a clip plane's {what} is three numbers, got {values!r:.60}") from None
    if len(numbers) != 3 or not all(math.isfinite(v) for v in numbers):
        raise VolrenError(f"a clip plane's {what} is three finite numbers, got {values!r:.60}")
    return numbers  # type: ignore[return-value]


@dataclass(frozen=True)
class ClipPlane:
    """A plane through `origin` (world units) keeping the side `normal` points to (the other side
    when `invert`). The normal need not be unit length, but must not be zero. A plane that is not
    `enabled` clips nothing and is kept only so that switching it on again brings it back (the
    app's plane list)."""

    origin: Triple
    normal: Triple
    invert: bool = False
    enabled: bool = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "origin", _triple(self.origin, "origin"))
        normal = _triple(self.normal, "normal")
        length = math.sqrt(sum(v * v for v in normal))
        if not (length > 0.0 and math.isfinite(length)):
            raise VolrenError(f"a clip plane's normal must not be zero, got {self.normal!r:.60}")
        object.__setattr__(self, "normal", normal)
        for name in ("invert", "enabled"):
            if not isinstance(getattr(self, name), bool):
                raise VolrenError(
                    f"a clip plane's {name} must be true or false, got {getattr(self, name)!r:.40}"
                )

    def half_space(self) -> tuple[float, float, float, float]:
        """(a, b, c, d) with a unit (a, b, c): the kept points satisfy a x + b y + c z + d >= 0."""
        length = math.sqrt(sum(v * v for v in self.normal))
        sign = -1.0 if self.invert else 1.0
        a, b, c = (sign * v / length for v in self.normal)
        return a, b, c, -(a * self.origin[0] + b * self.origin[1] + c * self.origin[2])

    def to_dict(self) -> dict[str, Any]:
        data: dict[str, Any] = {"origin": list(self.origin), "normal": list(self.normal)}
        if self.invert:
            data["invert"] = True
        if not self.enabled:
            data["enabled"] = False
        return data

    @classmethod
    def from_dict(cls, data: Any) -> ClipPlane:
        if not isinstance(data, Mapping):
            raise VolrenError(f"a clip plane is an object with 'origin' and 'normal', got {data!r:.60}")
        unknown = set(data) - {"origin", "normal", "invert", "enabled"}
        if unknown or "origin" not in data or "normal" not in data:
            raise VolrenError(
                f"a clip plane has 'origin', 'normal' and optional 'invert' and 'enabled', got keys {sorted(data)}"
            )
        return cls(data["origin"], data["normal"], data.get("invert", False), data.get("enabled", True))

    @classmethod
    def parse(cls, text: str) -> ClipPlane:
        """The CLI's form 'OX,OY,OZ,NX,NY,NZ' (the point, then the normal)."""
        parts = text.split(",")
        try:
            numbers = [float(p) for p in parts]
        except ValueError:
            numbers = []
        if len(numbers) != 6:
            raise VolrenError(
                f"a clip plane is six numbers OX,OY,OZ,NX,NY,NZ (a point, then the normal), got {text!r:.60}"
            )
        return cls(tuple(numbers[:3]), tuple(numbers[3:]))  # type: ignore[arg-type]


@dataclass(frozen=True)
class ClipRegion:
    """The kept region: inside every plane's kept side and inside `box` (None: no box).

    `cap` draws the cut faces opaque (Real-Time Volume Graphics, section 15.4: a clip surface
    that reads as a surface): where a ray enters the kept region through a plane or a face of the
    box, not through the volume's own boundary or the near plane, it meets a surface there of the
    TF's colour at the value at that point, opaque where the TF's opacity there is above zero
    (elsewhere the ray goes on), lit with the plane's normal when shading is on. Composite only.
    """

    planes: tuple[ClipPlane, ...] = ()
    box: Box | None = None
    cap: bool = False

    def __post_init__(self) -> None:
        if isinstance(self.planes, ClipPlane) or not isinstance(self.planes, Sequence):
            raise VolrenError(f"clip planes must be a list of planes, got {self.planes!r:.60}")
        planes = tuple(p if isinstance(p, ClipPlane) else _plane_from(p) for p in self.planes)
        if len(planes) > MAX_PLANES:
            raise VolrenError(f"at most {MAX_PLANES} clip planes, got {len(planes)}")
        object.__setattr__(self, "planes", planes)
        if self.box is not None:
            object.__setattr__(self, "box", check_box(self.box))
        if not isinstance(self.cap, bool):
            raise VolrenError(f"'clip.cap' must be true or false, got {self.cap!r:.40}")

    @property
    def is_empty(self) -> bool:
        """True when nothing is clipped (no box, and no plane switched on)."""
        return self.box is None and not any(p.enabled for p in self.planes)

    def half_spaces(self) -> NDArray[np.float64]:
        """(m, 4) rows (a, b, c, d): the kept points satisfy a x + b y + c z + d >= 0 for every row
        (the planes, then the box's faces that are finite)."""
        rows = [p.half_space() for p in self.planes if p.enabled]
        if self.box is not None:
            for axis in range(3):
                unit = [0.0, 0.0, 0.0]
                unit[axis] = 1.0
                rows.append((*unit, -self.box[2 * axis]))  # type: ignore[arg-type]
                unit[axis] = -1.0
                rows.append((*unit, self.box[2 * axis + 1]))  # type: ignore[arg-type]
        return np.array(rows, dtype=np.float64).reshape(-1, 4)

    def half_spaces_in_grid(self, origin: Sequence[float], spacing: Sequence[float]) -> NDArray[np.float64]:
        """`half_spaces` in the index space of a grid (world x = origin + spacing * i), where a
        ray caster marches."""
        world = self.half_spaces()
        out = world.copy()
        out[:, :3] = world[:, :3] * np.asarray(spacing, dtype=np.float64)
        out[:, 3] = world[:, 3] + world[:, :3] @ np.asarray(origin, dtype=np.float64)
        return out

    def keeps(self, points: NDArray[np.floating[Any]]) -> NDArray[np.bool_]:
        """Which of the (n, 3) world points lie in the kept region."""
        rows = self.half_spaces()
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        return np.all(pts @ rows[:, :3].T + rows[:, 3] >= 0.0, axis=1)

    def with_box(self, box: Box | None) -> ClipRegion:
        return ClipRegion(self.planes, box, self.cap)

    @property
    def caps(self) -> bool:
        """Whether cut faces are drawn: `cap` asked for and something is cut."""
        return self.cap and not self.is_empty

    def to_dict(self) -> dict[str, Any]:
        data: dict[str, Any] = {"planes": [p.to_dict() for p in self.planes]}
        if self.box is not None:
            data["box"] = list(self.box)
        if self.cap:
            data["cap"] = True
        return data

    @classmethod
    def from_dict(cls, data: Any) -> ClipRegion:
        if isinstance(data, ClipRegion):
            return data
        if not isinstance(data, Mapping):
            raise VolrenError(f"'clip' must be an object with 'planes' and 'box', got {data!r:.60}")
        unknown = set(data) - {"planes", "box", "cap"}
        if unknown:
            raise VolrenError(f"unknown clip keys {sorted(unknown)}; use planes, box, cap")
        planes = data.get("planes", [])
        if not isinstance(planes, Sequence) or isinstance(planes, str):
            raise VolrenError(f"'clip.planes' must be a list, got {planes!r:.60}")
        return cls(tuple(ClipPlane.from_dict(p) for p in planes), data.get("box"), data.get("cap", False))


NO_CLIP = ClipRegion()


def _plane_from(value: Any) -> ClipPlane:
    """A plane from a dict, or from a pair (origin, normal) as the Python API takes it."""
    if isinstance(value, Mapping):
        return ClipPlane.from_dict(value)
    if isinstance(value, Sequence) and not isinstance(value, str) and len(value) == 2:
        return ClipPlane(value[0], value[1])
    raise VolrenError(f"a clip plane is (origin, normal) or {{'origin', 'normal'}}, got {value!r:.60}")


def blend_clip_regions(a: ClipRegion, b: ClipRegion, weight: float) -> ClipRegion:
    """The region `weight` of the way from `a` to `b` (a movie between two clip keyframes): each
    plane's point moves on a straight line and its unit normal turns between the two (normalised
    linear blend), the box's sides move linearly; switches (invert, enabled) and a box present in
    only one key follow the nearer key. Both keys hold the same number of planes."""
    if len(a.planes) != len(b.planes):
        raise VolrenError(
            f"clip keyframes must hold the same number of planes, got {len(a.planes)} and {len(b.planes)}"
        )
    if weight <= 0.0:
        return a
    if weight >= 1.0:
        return b
    near = a if weight < 0.5 else b
    planes = []
    for pa, pb, pn in zip(a.planes, b.planes, near.planes, strict=True):
        origin = (1.0 - weight) * np.asarray(pa.origin) + weight * np.asarray(pb.origin)
        na = np.asarray(pa.normal) / np.linalg.norm(pa.normal)
        nb = np.asarray(pb.normal) / np.linalg.norm(pb.normal)
        normal = (1.0 - weight) * na + weight * nb
        if not np.linalg.norm(normal) > 1e-12:  # opposite normals half-way: keep the nearer key's
            normal = np.asarray(pn.normal, dtype=np.float64)
        planes.append(ClipPlane(tuple(origin), tuple(normal), pn.invert, pn.enabled))  # type: ignore[arg-type]
    box = near.box
    if a.box is not None and b.box is not None:
        box = tuple((1.0 - weight) * np.asarray(a.box) + weight * np.asarray(b.box))  # type: ignore[assignment]
    return ClipRegion(tuple(planes), box, near.cap)
