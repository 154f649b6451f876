"""Volumes: a uniform grid of samples, or a tetrahedral mesh with values at its points.

Axis order: `UniformVolume.values` is indexed ``values[k, j, i]`` (z, y, x), C-contiguous, so x
varies fastest in memory exactly as in VTK and in an OpenGL 3D texture. Spacing, origin and
bounds are given in (x, y, z) order. Sample ``[k, j, i]`` sits at ``origin + (i, j, k) * spacing``.

Non-finite values (NaN, +-Inf) are kept as they are, counted, and left out of the value range;
every renderer treats them as transparent.

A tetrahedron given more than once (the same points in any order, after merging repeated points)
is kept once, with a note: renderers disagreed on doubled cells (one drew them twice, another
not at all), and a cell is one piece of the domain however often a file lists it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import ClassVar, Literal, TypeAlias

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError
from volren.model.channels import ChannelSet
from volren.model.labels import LabelMap
from volren.model.settings import MAX_SAMPLES_PER_RAY
from volren.model.tet_repair import repeated_tets

VolumeKind: TypeAlias = Literal["uniform", "tet"]

#: Data types kept exactly as given; anything else is converted (and the conversion noted).
KEPT_DTYPES = (np.uint8, np.int16, np.uint16, np.float32, np.float64)

_CONVERSIONS = {
    np.dtype(np.bool_): np.uint8,
    np.dtype(np.int8): np.int16,
    np.dtype(np.float16): np.float32,
}


def normalize_dtype(values: NDArray, what: str) -> tuple[NDArray, tuple[str, ...]]:
    """Return `values` in a kept dtype, and a note when a conversion was needed.

    Wide integers go to float64, which is exact up to 2**53: no real scalar field comes close.
    Byte-swapped data (e.g. big-endian int16 from a file) is brought to native order, type kept.
    """
    if not values.dtype.isnative:
        values = values.astype(values.dtype.newbyteorder("="))
    dtype = values.dtype
    if any(dtype == np.dtype(kept) for kept in KEPT_DTYPES):
        return values, ()
    if dtype in _CONVERSIONS:
        target = np.dtype(_CONVERSIONS[dtype])
    elif np.issubdtype(dtype, np.integer):
        target = np.dtype(np.float64)
    elif np.issubdtype(dtype, np.floating):
        target = np.dtype(np.float64)
    else:
        raise VolrenError(f"{what}: scalar type {dtype} is not numeric")
    return values.astype(target), (f"{what}: {dtype} values converted to {target}",)


def finite_range(values: NDArray) -> tuple[tuple[float, float], int]:
    """(min, max) over the finite values, and how many values are not finite."""
    if np.issubdtype(values.dtype, np.integer):
        return (float(values.min()), float(values.max())), 0
    finite = np.isfinite(values)
    n_bad = int(values.size - np.count_nonzero(finite))
    if n_bad == values.size:
        return (0.0, 0.0), n_bad
    good = values[finite] if n_bad else values
    return (float(good.min()), float(good.max())), n_bad


def spanning(lo: float, hi: float) -> tuple[float, float]:
    """(lo, hi) with hi > lo, for a table over the range to divide by hi - lo: a constant range is
    widened by 1, or by a millionth of |lo| where adding 1 is lost to rounding (from about 1e16:
    lo + 1 == lo, and the division by zero ended the render)."""
    if hi > lo:
        return lo, hi
    return lo, lo + max(1.0, 1e-6 * abs(lo))


def merged_tets_note(name: str, count: int) -> str:
    """The note (and load warning) for `count` repeated tetrahedra kept once."""
    return f"{name}: {count:,} duplicated tetrahedr{'on' if count == 1 else 'a'} merged"


def _as_triple(value, what: str) -> tuple[float, float, float]:
    arr = np.asarray(value, dtype=np.float64).reshape(-1)
    if arr.size == 1:
        arr = np.repeat(arr, 3)
    if arr.size != 3 or not np.all(np.isfinite(arr)):
        raise VolrenError(f"{what} must be three finite numbers, got {value!r}")
    return (float(arr[0]), float(arr[1]), float(arr[2]))


#: The shortest step, in characteristic lengths, that a quality level takes (raycast's error target
#: stops at 1/8 of step 2; every level's finest is 0.25).
FINEST_LEVEL_STEP = 0.25


@dataclass(frozen=True, eq=False)
class UniformVolume:
    """Samples on a regular, axis-aligned grid (VTK image data)."""

    values: NDArray
    spacing: tuple[float, float, float] = (1.0, 1.0, 1.0)
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0)
    name: str = "volume"
    notes: tuple[str, ...] = ()
    #: The field the values are (an array name, or NAME:COMPONENT), and every field the source
    #: offers ("" and () for volumes made in memory): what the app's array chooser lists.
    scalars: str = ""
    arrays: tuple[str, ...] = ()
    #: the anatomical letter +x, +y, +z point toward ("L", "P", "S"), where the file says (`model.anatomy`)
    patient_axes: tuple[str, str, str] | None = None
    #: a segmentation on the same grid (`model.labels`): what a `LabelTransferFunction` classifies by
    labels: LabelMap | None = None
    #: several fields on the same grid (`model.channels`), `values` being one of them: what a
    #: `ChannelTransferFunction` mixes
    channels: ChannelSet | None = None
    value_range: tuple[float, float] = field(init=False)
    nonfinite_count: int = field(init=False)

    kind: ClassVar[VolumeKind] = "uniform"

    def __post_init__(self) -> None:
        values = np.asarray(self.values)
        if values.ndim != 3:
            raise VolrenError(f"{self.name}: a uniform volume needs 3D values, got shape {values.shape}")
        if values.size == 0:
            raise VolrenError(f"{self.name}: the grid is empty (shape {values.shape})")
        if min(values.shape) < 2:
            nx, ny, nz = values.shape[::-1]
            raise VolrenError(
                f"{self.name}: volume rendering needs at least 2 samples along each axis, got {nx}x{ny}x{nz}"
            )
        values, conversion = normalize_dtype(values, self.name)
        values = np.ascontiguousarray(values)
        spacing = _as_triple(self.spacing, f"{self.name}: spacing")
        if min(spacing) <= 0:
            raise VolrenError(f"{self.name}: spacing must be positive, got {spacing}")
        origin = _as_triple(self.origin, f"{self.name}: origin")
        if self.labels is not None:
            if not isinstance(self.labels, LabelMap):
                raise VolrenError(f"{self.name}: labels must be a LabelMap, got {type(self.labels).__name__}")
            self.labels.check_grid(values.shape, self.name)
        if self.channels is not None:
            if not isinstance(self.channels, ChannelSet):
                raise VolrenError(
                    f"{self.name}: channels must be a ChannelSet, got {type(self.channels).__name__}"
                )
            if self.channels.shape != values.shape:
                got, want = self.channels.shape[::-1], values.shape[::-1]
                raise VolrenError(f"{self.name}: the channels are {'x'.join(map(str, got))} but the volume is "
                                  f"{'x'.join(map(str, want))}: channels must lie on the volume's grid")  # fmt: skip
        value_range, n_bad = finite_range(values)
        if n_bad == values.size:
            raise VolrenError(f"{self.name}: no finite values (all {n_bad} are NaN or Inf)")
        notes = tuple(self.notes) + conversion
        if n_bad:
            notes += (f"{self.name}: {n_bad} non-finite values (NaN/Inf), rendered transparent",)
        for name, value in (
            ("values", values),
            ("spacing", spacing),
            ("origin", origin),
            ("notes", notes),
            ("value_range", value_range),
            ("nonfinite_count", n_bad),
        ):
            object.__setattr__(self, name, value)

    @classmethod
    def from_xyz(cls, values_xyz: NDArray, **kwargs) -> UniformVolume:
        """Build from an array indexed ``[i, j, k]`` (x, y, z), as PyVista's reshape(order='F') gives."""
        return cls(np.ascontiguousarray(np.asarray(values_xyz).transpose(2, 1, 0)), **kwargs)

    @property
    def dimensions(self) -> tuple[int, int, int]:
        """Number of samples along x, y, z."""
        nz, ny, nx = self.values.shape
        return (nx, ny, nz)

    @property
    def bounds(self) -> tuple[float, float, float, float, float, float]:
        """(xmin, xmax, ymin, ymax, zmin, zmax), VTK's order."""
        out = []
        for o, s, n in zip(self.origin, self.spacing, self.dimensions):
            out += [o, o + s * (n - 1)]
        return tuple(out)  # type: ignore[return-value]

    @property
    def mean_spacing(self) -> float:
        """The unit of the `step` render setting on uniform grids (the same sum and division as
        np.mean, without its ~18 us a call: renderers ask several times a frame)."""
        x, y, z = (float(v) for v in self.spacing)
        return (x + y + z) / 3.0

    @property
    def characteristic_length(self) -> float:
        """Length that `RenderSettings.step` is measured in: the smallest spacing, so that a step
        holds along the finest axis (in mean spacings, step 0.5 on a 0.5 x 0.5 x 5 grid is two x-y
        voxels and drops what is thinner). On a grid so anisotropic that the finest steps any
        quality level takes (`FINEST_LEVEL_STEP`) would exceed `MAX_SAMPLES_PER_RAY` across it (slices
        1e5 times farther apart than their pixels), the length those samples need instead, so that
        every level stays drawable."""
        b = self.bounds
        diagonal = math.hypot(b[1] - b[0], b[3] - b[2], b[5] - b[4])
        return max(min(self.spacing), diagonal / (FINEST_LEVEL_STEP * MAX_SAMPLES_PER_RAY))

    def __repr__(self) -> str:
        nx, ny, nz = self.dimensions
        return (
            f"UniformVolume({self.name!r}, {nx}x{ny}x{nz} {self.values.dtype}, "
            f"spacing={self.spacing}, range={self.value_range})"
        )


@dataclass(frozen=True, eq=False)
class TetVolume:
    """A tetrahedral mesh with a scalar value at each point (linear inside each tetrahedron)."""

    points: NDArray
    tets: NDArray
    values: NDArray
    name: str = "mesh"
    notes: tuple[str, ...] = ()
    scalars: str = ""  #: as in `UniformVolume`
    arrays: tuple[str, ...] = ()
    value_range: tuple[float, float] = field(init=False)
    nonfinite_count: int = field(init=False)
    merged_tet_count: int = field(init=False)  # repeated tetrahedra dropped (module docstring)

    kind: ClassVar[VolumeKind] = "tet"

    def __post_init__(self) -> None:
        points = np.ascontiguousarray(np.asarray(self.points, dtype=np.float64))
        tets = np.asarray(self.tets)
        values = np.asarray(self.values)
        if points.ndim != 2 or points.shape[1] != 3:
            raise VolrenError(f"{self.name}: points must have shape (n, 3), got {points.shape}")
        if tets.ndim != 2 or tets.shape[1] != 4:
            raise VolrenError(f"{self.name}: tets must have shape (m, 4), got {tets.shape}")
        if len(tets) == 0 or len(points) == 0:
            raise VolrenError(
                f"{self.name}: the mesh is empty ({len(points)} points, {len(tets)} tetrahedra)"
            )
        if not np.issubdtype(tets.dtype, np.integer):
            raise VolrenError(f"{self.name}: tetrahedron indices must be integers, got {tets.dtype}")
        tets = np.ascontiguousarray(tets, dtype=np.int64)
        if tets.min() < 0 or tets.max() >= len(points):
            raise VolrenError(
                f"{self.name}: tetrahedra refer to points outside 0..{len(points) - 1} "
                f"(indices {tets.min()}..{tets.max()})"
            )
        if not np.all(np.isfinite(points)):
            raise VolrenError(f"{self.name}: point coordinates contain NaN or Inf")
        if values.shape != (len(points),):
            raise VolrenError(
                f"{self.name}: need one scalar per point ({len(points)}), got shape {values.shape}"
            )
        values, conversion = normalize_dtype(values, self.name)
        values = np.ascontiguousarray(values)
        value_range, n_bad = finite_range(values)
        if n_bad == values.size:
            raise VolrenError(f"{self.name}: no finite values (all {n_bad} are NaN or Inf)")
        notes = tuple(self.notes) + conversion
        if n_bad:
            notes += (f"{self.name}: {n_bad} non-finite point values (NaN/Inf), rendered transparent",)
        repeated = repeated_tets(points, tets, values)
        n_repeated = int(np.count_nonzero(repeated))
        if n_repeated:
            tets = np.ascontiguousarray(tets[~repeated])
            notes += (merged_tets_note(self.name, n_repeated),)
        for name, value in (
            ("points", points),
            ("tets", tets),
            ("values", values),
            ("notes", notes),
            ("value_range", value_range),
            ("nonfinite_count", n_bad),
            ("merged_tet_count", n_repeated),
        ):
            object.__setattr__(self, name, value)

    @cached_property
    def bounds(self) -> tuple[float, float, float, float, float, float]:
        """(xmin, xmax, ymin, ymax, zmin, zmax) of the points, VTK's order (computed once: on
        oxygen's 1.2 M points each call took 13 ms, and the app asks for it per renderer on every
        preview request, which held a TF drag's previews back until the drag ended)."""
        lo = self.points.min(axis=0)
        hi = self.points.max(axis=0)
        return (lo[0], hi[0], lo[1], hi[1], lo[2], hi[2])

    @cached_property
    def mean_edge_length(self) -> float:
        """Mean length of the six edges of every tetrahedron: the unit of the `step` setting
        (computed once: renderers ask for it every frame)."""
        corners = [self.points[self.tets[:, k]] for k in range(4)]  # four (m, 3) gathers, not one (m, 4, 3)
        pairs = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))
        lengths = np.empty((len(pairs), len(self.tets)))
        for row, (a, b) in zip(lengths, pairs, strict=True):
            d = corners[a] - corners[b]
            np.sqrt(np.add.reduce(d * d, axis=1), out=row)  # np.linalg.norm's sums, without its copies
        return float(np.mean(lengths))

    @property
    def characteristic_length(self) -> float:
        """Length that `RenderSettings.step` is measured in."""
        return self.mean_edge_length

    def __repr__(self) -> str:
        return (
            f"TetVolume({self.name!r}, {len(self.points)} points, {len(self.tets)} tets, "
            f"{self.values.dtype}, range={self.value_range})"
        )


Volume: TypeAlias = UniformVolume | TetVolume
