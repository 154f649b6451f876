"""Hard scenes that no default was fitted to: thin tubes and sheets, tiny objects, noise, steps and
anisotropic spacing, on grids and on tetrahedral meshes.

Why: the shared scenes are large smooth bodies; settings fitted to them can drop a feature thinner
than the spacing between rays or samples (image-space refinement between rays that agree, a step
chosen from an estimate over rays that miss a vessel) and still score well on them. Each scene
here holds features of 0.5-3 voxels, drawn at every image size from 128^2 to 1024^2 by the
fidelity benchmark (`benchmarks.defaults_fidelity`) and `volren bench run --datasets hard`.

The fields are procedural and seeded, so every run draws the same volumes: features are
antialiased over one voxel (a value falls from full to zero across one voxel at the feature's
edge), as a scanner's point spread makes them, and stored as uint8 like most scans.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import UniformVolume, Volume
from volren.testing.scenes import lattice_volume

Triple = tuple[float, float, float]
#: The radii of tubes and the thicknesses of sheets, in voxels (the finest first).
FEATURE_SIZES = (0.5, 0.75, 1.0, 1.5, 2.0, 3.0)
#: The image sizes every hard scene is measured at.
IMAGE_SIZES = (128, 256, 512, 1024)


@dataclass(frozen=True)
class HardCase:
    """A named hard scene: how to build its volume, its TF, and the orbit camera's angles."""

    name: str
    what: str
    build: Callable[[], Volume]
    tf: Callable[[], TransferFunction1D]
    kind: str = "uniform"
    azimuth: float = 30.0
    elevation: float = 20.0
    zoom: float = 1.0


def _grid(dims: Sequence[int], spacing: Triple) -> tuple[NDArray, NDArray, NDArray]:
    """World coordinates (z, y, x order arrays, broadcastable) of a grid at the origin."""
    nx, ny, nz = dims
    z = (np.arange(nz) * spacing[2])[:, None, None]
    y = (np.arange(ny) * spacing[1])[None, :, None]
    x = (np.arange(nx) * spacing[0])[None, None, :]
    return x, y, z


def _segment_distance(x: NDArray, y: NDArray, z: NDArray, a: NDArray, b: NDArray) -> NDArray:
    """Distance from every point to the segment a-b."""
    ab = b - a
    t = ((x - a[0]) * ab[0] + (y - a[1]) * ab[1] + (z - a[2]) * ab[2]) / float(ab @ ab)
    t = np.clip(t, 0.0, 1.0)
    return np.sqrt((x - a[0] - t * ab[0]) ** 2 + (y - a[1] - t * ab[1]) ** 2 + (z - a[2] - t * ab[2]) ** 2)


def _edge(inside_by: NDArray, width: float = 1.0) -> NDArray:
    """1 where a point is inside a feature by at least half of `width`, 0 where outside by as much,
    linear between: a feature antialiased over `width` world units."""
    return np.clip(inside_by / width + 0.5, 0.0, 1.0)


def _to_uint8(field: NDArray) -> NDArray[np.uint8]:
    return np.rint(np.clip(field, 0.0, 1.0) * 255.0).astype(np.uint8)


def _random_segments(rng: np.random.Generator, extent: NDArray, count: int) -> list[tuple[NDArray, NDArray]]:
    """`count` segments between random points of the box [0, extent] inset by a tenth: oblique to
    every axis, crossing each other."""
    lo, hi = 0.1 * extent, 0.9 * extent
    return [(rng.uniform(lo, hi), rng.uniform(lo, hi)) for _ in range(count)]


def tube_field(dims: Sequence[int], spacing: Triple = (1.0, 1.0, 1.0), seed: int = 1,
               radius_unit: float | None = None) -> NDArray[np.float64]:  # fmt: skip
    """Random oblique tubes of every radius in FEATURE_SIZES (in units of the finest spacing, or
    `radius_unit`), two of each, values 1 inside, antialiased over that unit (z, y, x)."""
    rng = np.random.default_rng(seed)
    unit = radius_unit if radius_unit is not None else min(spacing)
    x, y, z = _grid(dims, spacing)
    extent = (np.asarray(dims) - 1) * np.asarray(spacing)
    field = np.zeros((dims[2], dims[1], dims[0]))
    radii = [r for r in FEATURE_SIZES for _ in range(2)]
    for (a, b), radius in zip(_random_segments(rng, extent, len(radii)), radii, strict=True):
        inside_by = radius * unit - _segment_distance(x, y, z, a, b)
        np.maximum(field, _edge(inside_by, unit), out=field)
    return field


def _vessel_tf() -> TransferFunction1D:
    """Bright tubes over a dim background, as a CT angiogram's vessels: transparent below 30."""
    return TransferFunction1D.from_dict({
        "version": 1, "range": [0, 255],
        "color": [[0, 0.6, 0.1, 0.1], [120, 0.9, 0.3, 0.2], [255, 1.0, 0.95, 0.8]],
        "opacity": [[0, 0.0], [30, 0.0], [120, 0.6], [255, 0.9]],
        "opacity_unit_distance": 1.0,
    })  # fmt: skip


def tubes() -> Volume:
    """Twelve oblique tubes, radii 0.5-3 voxels, over faint noise (0-12 of 255) below the TF."""
    dims = (96, 96, 96)
    field = tube_field(dims)
    noise = np.random.default_rng(2).uniform(0.0, 12.0 / 255.0, field.shape)
    return UniformVolume(_to_uint8(np.maximum(field, noise)), name="hard_tubes")


def sheets() -> Volume:
    """Six oblique discs of thickness 0.5-3 voxels and radius 30 (their rims show), crossing."""
    dims = (96, 96, 96)
    rng = np.random.default_rng(3)
    x, y, z = _grid(dims, (1.0, 1.0, 1.0))
    field = np.zeros((96, 96, 96))
    for thickness in FEATURE_SIZES:
        normal = rng.normal(size=3)
        normal /= np.linalg.norm(normal)
        centre = rng.uniform(30.0, 65.0, 3)
        dist = (x - centre[0]) * normal[0] + (y - centre[1]) * normal[1] + (z - centre[2]) * normal[2]
        radial = np.sqrt(
            np.maximum((x - centre[0]) ** 2 + (y - centre[1]) ** 2 + (z - centre[2]) ** 2 - dist**2, 0.0)
        )
        inside_by = np.minimum(thickness / 2.0 - np.abs(dist), 30.0 - radial)
        np.maximum(field, _edge(inside_by), out=field)
    return UniformVolume(_to_uint8(field), name="hard_sheets")


def _sheet_tf() -> TransferFunction1D:
    return TransferFunction1D.from_dict({
        "version": 1, "range": [0, 255],
        "color": [[0, 0.2, 0.4, 0.9], [255, 0.9, 0.9, 1.0]],
        "opacity": [[0, 0.0], [40, 0.0], [255, 0.7]],
        "opacity_unit_distance": 1.0,
    })  # fmt: skip


def specks() -> Volume:
    """Eighty tiny bright balls (radius 0.3-1.5 voxels) in a faint smooth fog."""
    dims = (80, 80, 80)
    rng = np.random.default_rng(4)
    x, y, z = _grid(dims, (1.0, 1.0, 1.0))
    c = 39.5
    fog = 0.25 * np.exp(-((x - c) ** 2 + (y - c) ** 2 + (z - c) ** 2) / (2.0 * 20.0**2))
    field = np.broadcast_to(fog, (80, 80, 80)).copy()
    for _ in range(80):
        centre = rng.uniform(8.0, 72.0, 3)
        radius = rng.uniform(0.3, 1.5)
        d = np.sqrt((x - centre[0]) ** 2 + (y - centre[1]) ** 2 + (z - centre[2]) ** 2)
        np.maximum(field, _edge(radius - d), out=field)
    return UniformVolume(_to_uint8(field), name="hard_specks")


def _speck_tf() -> TransferFunction1D:
    return TransferFunction1D.from_dict({
        "version": 1, "range": [0, 255],
        "color": [[0, 0.1, 0.3, 0.6], [64, 0.2, 0.5, 0.8], [128, 1.0, 0.8, 0.2], [255, 1.0, 1.0, 0.9]],
        "opacity": [[0, 0.0], [64, 0.02], [100, 0.02], [160, 0.9], [255, 0.95]],
        "opacity_unit_distance": 1.0,
    })  # fmt: skip


def noise() -> Volume:
    """A smooth blob under strong white noise (+-40 of 255): detail at the grid's own frequency."""
    dims = (80, 80, 80)
    x, y, z = _grid(dims, (1.0, 1.0, 1.0))
    c = 39.5
    blob = 0.8 * np.exp(-((x - c) ** 2 + (y - c) ** 2 + (z - c) ** 2) / (2.0 * 18.0**2))
    jitter = np.random.default_rng(5).uniform(-40.0 / 255.0, 40.0 / 255.0, (80, 80, 80))
    return UniformVolume(_to_uint8(blob + jitter), name="hard_noise")


def _noise_tf() -> TransferFunction1D:
    return TransferFunction1D.from_dict({
        "version": 1, "range": [0, 255],
        "color": [[0, 0.1, 0.1, 0.5], [128, 0.2, 0.8, 0.4], [255, 1.0, 0.9, 0.3]],
        "opacity": [[0, 0.0], [255, 0.25]],
        "opacity_unit_distance": 1.0,
    })  # fmt: skip


def _shell_tf() -> TransferFunction1D:
    """Two narrow peaks (a band TF): thin shells where the blob crosses 100 and 180, through the noise."""
    return TransferFunction1D.from_dict({
        "version": 1, "range": [0, 255],
        "color": [[0, 0.9, 0.5, 0.2], [140, 0.3, 0.8, 0.9], [255, 1.0, 1.0, 1.0]],
        "opacity": [[0, 0.0], [96, 0.0], [100, 0.7], [104, 0.0], [176, 0.0], [180, 0.9], [184, 0.0]],
        "opacity_unit_distance": 1.0,
    })  # fmt: skip


def _wall_tf() -> TransferFunction1D:
    """One narrow peak at half the tubes' value (a band TF): the walls of every tube as thin shells."""
    return TransferFunction1D.from_dict({
        "version": 1, "range": [0, 255],
        "color": [[0, 1.0, 0.9, 0.6], [255, 1.0, 0.9, 0.6]],
        "opacity": [[0, 0.0], [118, 0.0], [128, 0.8], [138, 0.0]],
        "opacity_unit_distance": 1.0,
    })  # fmt: skip


def steps() -> Volume:
    """Nested solids with hard (not antialiased) faces: a box of 100, a ball of 200, a rod of 255,
    and a one-voxel-thick plate of 160: values that jump between neighbouring voxels."""
    dims = (80, 80, 80)
    x, y, z = _grid(dims, (1.0, 1.0, 1.0))
    shape = (80, 80, 80)
    field = np.zeros(shape)
    box = (np.abs(x - 40) < 28) & (np.abs(y - 40) < 28) & (np.abs(z - 40) < 20)
    field[np.broadcast_to(box, shape)] = 100.0
    ball = (x - 35) ** 2 + (y - 45) ** 2 + (z - 40) ** 2 < 15.0**2
    field[np.broadcast_to(ball, shape)] = 200.0
    rod = ((x - 55) ** 2 + (z - 30) ** 2 < 3.0**2) & (np.abs(y - 40) < 35)
    field[np.broadcast_to(rod, shape)] = 255.0
    plate = (np.abs(x + y - 70.0) < 0.75) & (np.abs(z - 60) < 15)
    field[np.broadcast_to(plate, shape)] = 160.0
    return UniformVolume(field.astype(np.uint8), name="hard_steps")


def _steps_tf() -> TransferFunction1D:
    """Opaque steps: the box faint, the ball and the plate half opaque, the rod solid."""
    return TransferFunction1D.from_dict({
        "version": 1, "range": [0, 255],
        "color": [[0, 0.5, 0.5, 0.5], [100, 0.3, 0.6, 1.0], [160, 0.2, 1.0, 0.3], [200, 1.0, 0.5, 0.2],
                  [255, 1.0, 1.0, 1.0]],
        "opacity": [[0, 0.0], [90, 0.0], [100, 0.02], [150, 0.02], [160, 0.6], [200, 0.6], [255, 1.0]],
        "opacity_unit_distance": 1.0,
    })  # fmt: skip


def anisotropic() -> Volume:
    """Tubes of radius 0.5-3 world units (1-6 x-y voxels) on a grid ten times coarser along z
    (0.5 x 0.5 x 5): every tube is thinner than one z spacing."""
    dims, spacing = (160, 160, 16), (0.5, 0.5, 5.0)
    field = tube_field(dims, spacing, seed=6, radius_unit=1.0)
    return UniformVolume(_to_uint8(field), spacing=spacing, name="hard_anisotropic")


def _tet_struts_field(x: NDArray, y: NDArray, z: NDArray) -> NDArray:
    """Oblique struts of radius 0.5-3 lattice units through a 24^3 lattice (a bracket's members)."""
    rng = np.random.default_rng(7)
    extent = np.full(3, 23.0)
    field = np.zeros_like(x, dtype=np.float64)
    for (a, b), radius in zip(_random_segments(rng, extent, len(FEATURE_SIZES)), FEATURE_SIZES, strict=True):
        np.maximum(field, _edge(radius - _segment_distance(x, y, z, a, b)), out=field)
    return 255.0 * field


def tet_struts() -> Volume:
    """A Kuhn-tetrahedralized 24^3 lattice (73,002 tets) holding oblique struts, radii 0.5-3."""
    return lattice_volume("tet", _tet_struts_field, (24, 24, 24), name="hard_tet_struts")


def _tet_sheets_field(x: NDArray, y: NDArray, z: NDArray) -> NDArray:
    """Two crossing oblique sheets, 0.5 and 1 lattice unit thick."""
    field = np.zeros_like(x, dtype=np.float64)
    for normal, offset, thickness in (((1.0, 2.0, 2.0), 33.0, 0.5), ((2.0, -1.0, 1.5), 12.0, 1.0)):
        n = np.asarray(normal) / np.linalg.norm(normal)
        dist = x * n[0] + y * n[1] + z * n[2] - offset
        np.maximum(field, _edge(thickness / 2.0 - np.abs(dist)), out=field)
    return 255.0 * field


def tet_sheets() -> Volume:
    """A Kuhn-tetrahedralized 24^3 lattice holding two crossing oblique sheets, 0.5 and 1 unit thick."""
    return lattice_volume("tet", _tet_sheets_field, (24, 24, 24), name="hard_tet_sheets")


CASES: dict[str, HardCase] = {case.name: case for case in (
    HardCase("hard_tubes", "oblique tubes, radii 0.5-3 voxels, over faint noise", tubes, _vessel_tf),
    HardCase("hard_sheets", "oblique discs 0.5-3 voxels thick", sheets, _sheet_tf, azimuth=60.0, elevation=35.0),
    HardCase("hard_specks", "tiny bright balls, radii 0.3-1.5 voxels, in fog", specks, _speck_tf),
    HardCase("hard_noise", "a smooth blob under white noise", noise, _noise_tf),
    HardCase("hard_shells", "thin iso-shells of a blob under noise (band TF)", noise, _shell_tf, azimuth=50.0),
    HardCase("hard_walls", "the walls of tubes 0.5-3 voxels thick (band TF)", tubes, _wall_tf, elevation=40.0),
    HardCase("hard_steps", "nested solids with hard faces, a one-voxel plate", steps, _steps_tf, azimuth=20.0),
    HardCase("hard_anisotropic", "tubes on a 1:1:10 grid", anisotropic, _vessel_tf, elevation=50.0),
    HardCase("hard_tet_struts", "oblique struts in a tetrahedral mesh", tet_struts, _vessel_tf, kind="tet"),
    HardCase("hard_tet_sheets", "oblique sheets in a tetrahedral mesh", tet_sheets, _sheet_tf, kind="tet",
             azimuth=45.0),
)}  # fmt: skip
