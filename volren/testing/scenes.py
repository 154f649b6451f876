"""The conformance kit's scenes: small volumes of either kind with the same point values, and
the cameras that make their closed forms simple.

Why both kinds from one function: a check is written once, against point values on a lattice; a
uniform grid samples them trilinearly, a tetrahedral mesh (each lattice cube split into the six
Kuhn tetrahedra) linearly per cell. Linear fields and constants are reproduced exactly by both,
so one closed form serves both kinds.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import NDArray

from volren.model.camera import Camera
from volren.model.volume import TetVolume, UniformVolume, Volume

Triple = tuple[float, float, float]
#: Point values as a function of world coordinates (arrays x, y, z of equal shape).
Field = Callable[[NDArray, NDArray, NDArray], NDArray]


def lattice_points(dims: Sequence[int], spacing: Triple, origin: Triple) -> NDArray[np.float64]:
    """Lattice points (N, 3), x varying fastest (VTK's point order)."""
    nx, ny, nz = dims
    k, j, i = np.meshgrid(np.arange(nz), np.arange(ny), np.arange(nx), indexing="ij")
    pts = np.stack([origin[0] + i * spacing[0], origin[1] + j * spacing[1], origin[2] + k * spacing[2]], -1)
    return pts.reshape(-1, 3).astype(np.float64)


def kuhn_tetrahedra(dims: Sequence[int]) -> NDArray[np.int64]:
    """Each lattice cube as the six tetrahedra around its main diagonal, positively oriented.

    The split is the same in every cube and symmetric under point reflection, so a field that is
    symmetric about a lattice point stays symmetric after linear interpolation."""
    nx, ny, nz = dims
    tets = []
    for kk, jj, ii in itertools.product(range(nz - 1), range(ny - 1), range(nx - 1)):
        corner = {
            (a, b, c): ((kk + c) * ny + jj + b) * nx + ii + a for a in (0, 1) for b in (0, 1) for c in (0, 1)
        }
        for order in itertools.permutations(range(3)):
            v = [0, 0, 0]
            path = [corner[tuple(v)]]
            for axis in order:
                v[axis] = 1
                path.append(corner[tuple(v)])
            tets.append(path)
    return np.array(tets, dtype=np.int64)


def positively_oriented(points: NDArray, tets: NDArray) -> NDArray:
    """`tets` with the last two corners swapped where the signed volume is negative."""
    p = points[tets]
    signed = np.einsum("ij,ij->i", p[:, 1] - p[:, 0], np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]))
    out = tets.copy()
    out[signed < 0] = out[signed < 0][:, [0, 1, 3, 2]]
    return out


def lattice_volume(
    kind: str,
    values: Field | float,
    dims: Sequence[int],
    spacing: Triple = (1.0, 1.0, 1.0),
    origin: Triple = (0.0, 0.0, 0.0),
    name: str = "kit",
) -> Volume:
    """A uniform grid (`kind` "uniform") or a Kuhn-tetrahedralized lattice ("tet") with the point
    values `values(x, y, z)` (or a constant)."""
    pts = lattice_points(dims, spacing, origin)
    if callable(values):
        point_values = np.asarray(values(pts[:, 0], pts[:, 1], pts[:, 2]), dtype=np.float64)
    else:
        point_values = np.full(len(pts), float(values))
    if kind == "uniform":
        nx, ny, nz = dims
        return UniformVolume(point_values.reshape(nz, ny, nx), spacing=spacing, origin=origin, name=name)
    if kind == "tet":
        return TetVolume(pts, positively_oriented(pts, kuhn_tetrahedra(dims)), point_values, name=name)
    raise ValueError(f"no kit scenes for {kind} volumes")


def axis_camera(
    bounds: Sequence[float],
    axis: int,
    sign: float,
    scale: float,
    parallel: bool = True,
    shift: Sequence[float] = (0.0, 0.0, 0.0),
) -> Camera:
    """A camera on the box's centre line along world `axis` (moved by `shift`), on the `sign`
    side, looking back."""
    b = np.asarray(bounds, dtype=np.float64)
    centre = (b[0::2] + b[1::2]) / 2.0 + np.asarray(shift, dtype=np.float64)
    direction = np.zeros(3)
    direction[axis] = sign
    extent = float(np.max(b[1::2] - b[0::2]))
    up = np.zeros(3)
    up[(axis + 2) % 3] = 1.0
    return Camera(
        position=tuple(centre + 4.0 * extent * direction),
        focal_point=tuple(centre),
        view_up=tuple(up),
        parallel=parallel,
        parallel_scale=scale,
        clipping_range=(0.5 * extent, 10.0 * extent),
    )


def column_camera(dims: Sequence[int], spacing: Triple, origin: Triple, z_top: float) -> Camera:
    """A parallel camera along -z whose nx x ny pixel centres lie on the lattice columns."""
    nx, ny, _ = dims
    cx = origin[0] + (nx - 1) * spacing[0] / 2.0
    cy = origin[1] + (ny - 1) * spacing[1] / 2.0
    return Camera(
        position=(cx, cy, z_top + 10.0),
        focal_point=(cx, cy, z_top),
        parallel=True,
        parallel_scale=ny * spacing[1] / 2.0,
        clipping_range=(1.0, 100.0 + z_top),
    )


def distant_camera_cut_by_far_plane(bounds: Sequence[float], cut: float, parallel: bool) -> Camera:
    """A user camera far out along an oblique direction with the default clipping range (far =
    1000.01), placed so that the far plane cuts the box `bounds` `cut` of the way through its depth:
    what `Camera.orbit` never makes (it fits the clipping range to the data), and what a camera
    from a script or a scene file can (renderers that ignored the planes drew the whole box)."""
    b = np.asarray(bounds, dtype=np.float64)
    centre = (b[0::2] + b[1::2]) / 2
    out = np.array([0.3, -0.4, 1.0]) / np.linalg.norm([0.3, -0.4, 1.0])  # toward the eye
    corners = np.array([[x, y, z] for x in b[0:2] for y in b[2:4] for z in b[4:6]])
    reach = float(np.abs((corners - centre) @ out).max())  # depths span distance -+ reach
    distance = Camera().clipping_range[1] + reach - 2 * reach * cut
    return Camera(position=tuple(centre + distance * out), focal_point=tuple(centre), parallel=parallel,
                  parallel_scale=0.6 * (b[3] - b[2]), view_angle=1.2)  # fmt: skip
