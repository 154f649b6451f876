"""VTK datasets (seen through `_pv.DatasetView`) to model volumes.

Both file loading and `from_pyvista` end here, so the rules are the same for both: which array is
the scalar field, cell data averaged onto points, tetrahedralization and tet repair, what is
reported. Everything repaired or ignored is reported once per load as a VolrenWarning and kept
in the volume's `notes`.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError, VolrenWarning
from volren.io import _pv
from volren.io.formats.base import Grid, is_identity
from volren.model.tet_repair import repair_tets
from volren.model.volume import TetVolume, UniformVolume, Volume, merged_tets_note

_CELL_NAMES = {
    11: ("voxel", "voxels"), 12: ("hexahedron", "hexahedra"), 13: ("wedge", "wedges"),
    14: ("pyramid", "pyramids"), 15: ("pentagonal prism", "pentagonal prisms"),
    16: ("hexagonal prism", "hexagonal prisms"), 42: ("polyhedron", "polyhedra"),
    1: ("vertex", "vertices"), 2: ("poly-vertex", "poly-vertices"), 3: ("line", "lines"),
    4: ("poly-line", "poly-lines"), 5: ("triangle", "triangles"), 6: ("triangle strip", "triangle strips"),
    7: ("polygon", "polygons"), 8: ("pixel", "pixels"), 9: ("quad", "quads"),
}  # fmt: skip


def _count(n: int, cell_type: int) -> str:
    if cell_type in _CELL_NAMES:
        one, many = _CELL_NAMES[cell_type]
    else:
        one = _pv.cell_type_class(cell_type).removeprefix("vtk")
        many = f"{one} cells"
    return f"{n:,} {one if n == 1 else many}"


def _counts(counts: dict[int, int]) -> str:
    return ", ".join(_count(n, t) for t, n in sorted(counts.items(), key=lambda kv: -kv[1]))


def warn(notes: list[str]) -> None:
    for note in notes:
        warnings.warn(note, VolrenWarning, stacklevel=4)


# --------------------------------------------------------------------------- choosing the array


def _usable(arrays: dict[str, NDArray], name: str | None) -> bool:
    return name is not None and name in arrays and arrays[name].dtype.kind in "biuf"


def _first(arrays: dict[str, NDArray], active: str | None) -> str | None:
    if _usable(arrays, active):
        return active
    for name, arr in arrays.items():
        if arr.dtype.kind in "biuf" and not name.startswith("vtk"):
            return name
    return None


def choose_array(view: _pv.DatasetView, scalars: str | None, source: str) -> tuple[str, str]:
    """(array name, 'point' or 'cell'): the named array, else the active or first point array."""
    points, cells = dict(view.point_arrays), dict(view.cell_arrays)
    if scalars is None:
        name = _first(points, view.active_point)
        if name is not None:
            return name, "point"
        name = _first(cells, view.active_cell)
        if name is not None:
            return name, "cell"
        raise VolrenError(f"{source}: no scalar arrays (neither point nor cell data)")
    if scalars in points:
        return scalars, "point"
    if scalars in cells:
        return scalars, "cell"
    available = [f"'{n}'" for n in points] + [f"'{n}' (cell data)" for n in cells]
    raise VolrenError(
        f"{source}: no array named {scalars!r}; available: {', '.join(available) if available else 'none'}"
    )


def _one_component(values: NDArray, name: str, source: str) -> NDArray:
    if values.ndim == 2 and values.shape[1] == 1:
        values = values[:, 0]
    if values.ndim != 1:
        raise VolrenError(
            f"{source}: array '{name}' has {values.shape[1]} components; volren renders a scalar "
            f"field: choose a 1-component array with scalars=..."
        )
    if values.dtype.kind not in "biuf":
        raise VolrenError(f"{source}: array '{name}' is not numeric ({values.dtype})")
    return values


def point_values(
    view: _pv.DatasetView, scalars: str | None, source: str, name: str
) -> tuple[_pv.DatasetView, NDArray, list[str]]:
    """The dataset (cell data moved to points if needed), its point scalars, and notes."""
    array, where = choose_array(view, scalars, source)
    notes = []
    if where == "cell":
        _one_component(view.cell_arrays[array], array, source)
        view = _pv.cell_to_point(view)
        notes.append(f"{name}: array '{array}' is cell data; averaged it onto the points")
    return view, _one_component(view.point_arrays[array], array, source), notes


# ------------------------------------------------------------------------------- uniform grids


def grid_from_view(view: _pv.DatasetView, scalars: str | None, source: str, name: str) -> Grid:
    """values[k, j, i] and geometry of image data (VTK's point order is x fastest)."""
    if view.n_points == 0:
        raise VolrenError(f"{source}: the grid is empty (0 points)")
    view, values, notes = point_values(view, scalars, source, name)
    nx, ny, nz = view.dimensions
    if values.size != nx * ny * nz:
        raise VolrenError(
            f"{source}: dimensions do not match the data: {nx}x{ny}x{nz} points but {values.size} values"
        )
    return Grid(values.reshape(nz, ny, nx), view.spacing, view.origin, view.direction, notes)


def volume_from_grid(grid: Grid, name: str) -> UniformVolume:
    """The model volume; a rotated grid is drawn axis-aligned, negative spacing flips the axis."""
    notes = list(grid.notes)
    if not is_identity(grid.direction):
        matrix = np.round(np.asarray(grid.direction), 4).tolist()
        notes.append(f"{name}: ignored the direction matrix {matrix}; the volume is drawn axis-aligned")
    values = grid.values
    spacing, origin = list(grid.spacing), list(grid.origin)
    for axis in range(3):  # x, y, z; numpy axis 2 - axis
        if spacing[axis] < 0:
            n = values.shape[2 - axis]
            origin[axis] += spacing[axis] * (n - 1)
            spacing[axis] = -spacing[axis]
            values = np.flip(values, axis=2 - axis)
    volume = UniformVolume(
        np.ascontiguousarray(values), tuple(spacing), tuple(origin), name=name, notes=tuple(notes + grid.info)
    )
    _report(volume, notes)
    return volume


def _report(volume: Volume, notes: list[str]) -> None:
    warn(notes)
    if volume.nonfinite_count:
        warn([f"{volume.name}: {volume.nonfinite_count:,} values are NaN or Inf; they render transparent"])
    if isinstance(volume, TetVolume) and volume.merged_tet_count:
        warn([merged_tets_note(volume.name, volume.merged_tet_count)])


# ---------------------------------------------------------------------------- tetrahedral meshes


def tets_from_view(view: _pv.DatasetView, scalars: str | None, source: str, name: str) -> TetVolume:
    """Point scalars on tetrahedra: other 3D cells split, lower-dimensional cells dropped, tets repaired."""
    if view.n_points == 0 or view.n_cells == 0:
        raise VolrenError(f"{source}: the grid is empty ({view.n_points} points, {view.n_cells} cells)")
    view, values, notes = point_values(view, scalars, source, name)
    cells = _pv.tetrahedralize(view)
    broken = ", ".join(f"{n:,} {why}" for why, n in cells.broken.items())
    if len(cells.tets) == 0:
        held = broken or _counts(cells.dropped)
        raise VolrenError(f"{source}: no 3D cells to render (the grid holds {held})")
    repaired = repair_tets(cells.points, cells.tets)
    if len(repaired.tets) == 0:
        raise VolrenError(f"{source}: all {len(cells.tets):,} tetrahedra have zero volume")
    done = []
    if broken:
        done.append(f"dropped broken cells: {broken}")
    if cells.tetrahedralized:
        done.append(f"tetrahedralized {_counts(cells.tetrahedralized)}")
    if cells.dropped:
        n = sum(cells.dropped.values())
        which = "cells that are" if n > 1 else "cell that is"
        done.append(f"dropped {n:,} {which} not 3D ({_counts(cells.dropped)})")
    if repaired.dropped_degenerate:
        n = repaired.dropped_degenerate
        done.append(f"dropped {n:,} zero-volume tetrahedr{'on' if n == 1 else 'a'}")
    if repaired.reoriented:
        n = repaired.reoriented
        done.append(f"reoriented {n:,} inverted {'one' if n == 1 else 'ones'}")
    repairs = [f"{name}: {', '.join(done)}"] if done else []
    notes = notes + repairs
    volume = TetVolume(cells.points, repaired.tets, values, name=name, notes=tuple(notes))
    _report(volume, notes)
    return volume


# ------------------------------------------------------------------------------------ pyvista


def volume_from_view(view: _pv.DatasetView, scalars: str | None, source: str, name: str) -> Volume:
    if view.kind == "image":
        return volume_from_grid(grid_from_view(view, scalars, source, name), name)
    return tets_from_view(view, scalars, source, name)


def from_pyvista(dataset: Any, scalars: str | None = None, name: str = "dataset") -> Volume:
    """A model volume from an in-memory pyvista (or VTK) dataset.

    Image data becomes a `UniformVolume`; anything else is cast to an unstructured grid and
    tetrahedralized into a `TetVolume`.
    """
    wrapped = _pv.as_dataset(dataset)
    if wrapped is None:
        raise VolrenError(f"{name}: expected a pyvista or VTK dataset, got {type(dataset).__name__}")
    return volume_from_view(_pv.view(wrapped), scalars, name, name)
