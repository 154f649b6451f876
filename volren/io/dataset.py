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
from volren.io.channel_io import ChannelPick, PickedChannels, check_pick, nonfinite_notes, wants_pick
from volren.io.formats.base import Grid, is_identity
from volren.model.anatomy import patient_axes
from volren.model.tet_mesh import folded_cells
from volren.model.tet_repair import merged_duplicates, repair_tets
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


#: What follows "NAME:" in an array choice: one component of a vector array, or its length.
MAGNITUDE = "magnitude"
_XYZ = ("x", "y", "z")


def _components(values: NDArray) -> int:
    return 1 if values.ndim == 1 else int(values.shape[1])


def _component_names(count: int) -> list[str]:
    """How the components of a `count`-component array are named in a choice: x, y, z for
    vectors of 2 or 3 (as ParaView shows them), else their indices."""
    return list(_XYZ[:count]) if count <= 3 else [str(i) for i in range(count)]


def _numeric(name: str, values: NDArray) -> bool:
    return values.dtype.kind in "biuf" and not name.startswith("vtk")


def array_choices(view: _pv.DatasetView) -> tuple[str, ...]:
    """Every scalar field this dataset offers, as `scalars` names: a 1-component array by its
    name; a vector as NAME:magnitude and NAME:x (y, z, or 0, 1, ...); point arrays first."""
    choices: list[str] = []
    for arrays in (view.point_arrays, view.cell_arrays):
        for name, values in arrays.items():
            if not _numeric(name, values) or values.ndim > 2:
                continue
            count = _components(values)
            named = (
                [name]
                if count == 1
                else [f"{name}:{MAGNITUDE}"] + [f"{name}:{c}" for c in _component_names(count)]
            )
            choices += [choice for choice in named if choice not in choices]
    return tuple(choices)


def _first(arrays: dict[str, NDArray], active: str | None) -> str | None:
    if active is not None and active in arrays and arrays[active].dtype.kind in "biuf":
        return active
    for name, arr in arrays.items():
        if _numeric(name, arr):
            return name
    return None


def _split_choice(scalars: str, points: dict, cells: dict) -> tuple[str, str | None]:
    """(array name, component or None): an existing array's own name wins over NAME:COMPONENT."""
    if scalars in points or scalars in cells:
        return scalars, None
    name, sep, component = scalars.rpartition(":")
    if sep and (name in points or name in cells):
        return name, component.strip().lower()
    return scalars, None


def choose_array(view: _pv.DatasetView, scalars: str | None, source: str) -> tuple[str, str, str | None]:
    """(array name, 'point' or 'cell', component): the named array (NAME, or NAME:COMPONENT for a
    vector's component or magnitude), else the active or first point array."""
    points, cells = dict(view.point_arrays), dict(view.cell_arrays)
    if scalars is None:
        name = _first(points, view.active_point)
        if name is not None:
            return name, "point", None
        name = _first(cells, view.active_cell)
        if name is not None:
            return name, "cell", None
        raise VolrenError(f"{source}: no scalar arrays (neither point nor cell data)")
    name, component = _split_choice(scalars, points, cells)
    if name in points:
        return name, "point", component
    if name in cells:
        return name, "cell", component
    available = [f"'{n}'" for n in array_choices(view)]
    raise VolrenError(
        f"{source}: no array named {scalars!r}; available: {', '.join(available) if available else 'none'}"
    )


def _scalar_field(values: NDArray, name: str, component: str | None, source: str) -> tuple[NDArray, str]:
    """The 1-component field an array gives, and its choice name: the array itself, one
    component, or the magnitude (the default for a vector, as in ParaView)."""
    if values.dtype.kind not in "biuf":
        raise VolrenError(f"{source}: array '{name}' is not numeric ({values.dtype})")
    count = _components(values)
    if values.ndim > 2:
        raise VolrenError(f"{source}: array '{name}' has shape {values.shape}; volren renders a scalar field")
    if count == 1:
        if component is not None and component not in ("0", "x", MAGNITUDE):
            raise VolrenError(
                f"{source}: array '{name}' has one component; there is no component {component!r}"
            )
        return values.reshape(-1), name
    names = _component_names(count)
    if component is None or component == MAGNITUDE:
        wide = values.astype(np.float64)
        magnitude = np.sqrt(np.einsum("ij,ij->i", wide, wide))
        keep = values.dtype if values.dtype.kind == "f" and values.dtype.itemsize >= 4 else np.float64
        return magnitude.astype(keep, copy=False), f"{name}:{MAGNITUDE}"
    if component in names:
        index = names.index(component)
    elif component.isdigit() and int(component) < count:
        index = int(component)
    else:
        options = ", ".join(f"{name}:{c}" for c in [MAGNITUDE, *names])
        raise VolrenError(f"{source}: array '{name}' has {count} components; no component {component!r} "
                          f"(choose {options})")  # fmt: skip
    return np.ascontiguousarray(values[:, index]), f"{name}:{names[index]}"


def point_values(
    view: _pv.DatasetView, scalars: str | None, source: str, name: str
) -> tuple[_pv.DatasetView, NDArray, list[str], list[str], str]:
    """The dataset (cell data moved to points if needed), its point scalars, notes (warned),
    info (only recorded), and the choice name of the field (NAME, or NAME:COMPONENT)."""
    array, where, component = choose_array(view, scalars, source)
    notes, info = [], []
    if where == "cell":
        _scalar_field(view.cell_arrays[array], array, component, source)  # refuse before averaging
        view = _pv.cell_to_point(view)
        notes.append(f"{name}: array '{array}' is cell data; averaged it onto the points")
    values, chosen = _scalar_field(view.point_arrays[array], array, component, source)
    if component is None and chosen != array:  # ParaView's default too: a choice, not a repair
        info.append(f"{name}: array '{array}' has {_components(view.point_arrays[array])} components; showing its "
                    f"magnitude (or choose {array}:x, ...)")  # fmt: skip
    return view, values, notes, info, chosen


# ------------------------------------------------------------------------------- uniform grids


def grid_from_view(
    view: _pv.DatasetView, scalars: str | None, source: str, name: str, channels: ChannelPick = None
) -> Grid:
    """values[k, j, i] and geometry of image data (VTK's point order is x fastest); with `channels`
    (True or the component numbers, `volren.io.channel_io`), the array's components as channels."""
    if view.n_points == 0:
        raise VolrenError(f"{source}: the grid is empty (0 points)")
    choices = array_choices(view)
    if wants_pick(channels):
        return _channel_grid(view, scalars, source, name, channels, choices)
    view, values, notes, info, chosen = point_values(view, scalars, source, name)
    nx, ny, nz = view.dimensions
    if values.size != nx * ny * nz:
        raise VolrenError(
            f"{source}: dimensions do not match the data: {nx}x{ny}x{nz} points but {values.size} values"
        )
    return Grid(values.reshape(nz, ny, nx), view.spacing, view.origin, view.direction, notes, info, scalars=chosen,
                arrays=choices)  # fmt: skip


def _channel_grid(view: _pv.DatasetView, scalars: str | None, source: str, name: str, channels: ChannelPick,
                  choices: tuple[str, ...]) -> Grid:  # fmt: skip
    """The grid of an array's components as channels (Max 1995's several media on one grid): the
    picked ones, [c, k, j, i], named by VTK's component names where the file has them, else NAME:c."""
    array, where, component = choose_array(view, scalars, source)
    if component is not None:
        raise VolrenError(f"{source}: channels are an array's components; give the array's name ({array!r}), "
                          f"not {scalars!r}")  # fmt: skip
    arrays = view.point_arrays if where == "point" else view.cell_arrays
    count = _components(arrays[array])
    if arrays[array].dtype.kind not in "biuf" or arrays[array].ndim > 2:
        _scalar_field(arrays[array], array, None, source)  # refused there, in its words
    if count == 1:
        raise VolrenError(f"{source}: array '{array}' has one component; channels come from an array of several "
                          "components (or an OME-Zarr image's c axis)")  # fmt: skip
    picked = check_pick(channels, count, f"{source}: array '{array}' has {count} components")
    given = view.component_names.get(array, ())
    names = tuple(str(given[c]) if c < len(given) and given[c] else f"{array}:{c}" for c in picked)
    notes: list[str] = []
    if where == "cell":
        view = _pv.cell_to_point(view)
        notes.append(f"{name}: array '{array}' is cell data; averaged it onto the points")
    values = view.point_arrays[array]
    nx, ny, nz = view.dimensions
    if values.shape[0] != nx * ny * nz:
        raise VolrenError(f"{source}: dimensions do not match the data: {nx}x{ny}x{nz} points but "
                          f"{values.shape[0]} values")  # fmt: skip
    stacked = np.ascontiguousarray(values[:, list(picked)].T).reshape(len(picked), nz, ny, nx)
    info = [f"{name}: array '{array}' read as {len(picked)} channels ({', '.join(names)})"]
    return Grid(stacked[0], view.spacing, view.origin, view.direction, notes, info, scalars=names[0],
                arrays=choices, channels=stacked, channel_names=names, channel_indices=picked)  # fmt: skip


def volume_from_grid(grid: Grid, name: str) -> UniformVolume:
    """The model volume; a rotated grid is drawn axis-aligned, negative spacing flips the axis."""
    notes = list(grid.notes)
    flips = tuple(s < 0 for s in grid.spacing)
    anatomy = patient_axes(grid.direction, grid.space, flips)
    if not is_identity(grid.direction):
        matrix = np.round(np.asarray(grid.direction), 4).tolist()
        notes.append(f"{name}: ignored the direction matrix {matrix}; the volume is drawn axis-aligned")
    values = grid.values
    stacked = grid.channels
    spacing, origin = list(grid.spacing), list(grid.origin)
    for axis in range(3):  # x, y, z; numpy axis 2 - axis
        if spacing[axis] < 0:
            n = values.shape[2 - axis]
            origin[axis] += spacing[axis] * (n - 1)
            spacing[axis] = -spacing[axis]
            values = np.flip(values, axis=2 - axis)
            stacked = None if stacked is None else np.flip(stacked, axis=3 - axis)
    channels = None
    if stacked is not None:
        channels = PickedChannels(np.ascontiguousarray(stacked), grid.channel_names, name=name,
                                  indices=grid.channel_indices)  # fmt: skip
        values = channels.values[0]  # a view: the channels hold the one copy
        notes += nonfinite_notes(channels, name)
    volume = UniformVolume(
        np.ascontiguousarray(values),
        tuple(spacing),
        tuple(origin),
        name=name,
        notes=tuple(notes + grid.info),
        scalars=grid.scalars,
        arrays=grid.arrays,
        patient_axes=anatomy,
        channels=channels,
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
    choices = array_choices(view)
    view, values, notes, info, chosen = point_values(view, scalars, source, name)
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
        done.append(f"reoriented {n:,} inverted tetrahedr{'on' if n == 1 else 'a'}")
    repairs = [f"{name}: {', '.join(done)}"] if done else []
    notes = notes + repairs + _folds_note(cells.points, repaired.tets, values, name)
    volume = TetVolume(cells.points, repaired.tets, values, name=name, notes=tuple(notes + info), scalars=chosen,
                       arrays=choices)  # fmt: skip
    _report(volume, notes)
    return volume


def _folds_note(points: NDArray, tets: NDArray, values: NDArray, name: str) -> list[str]:
    """The note on tetrahedra that fold over a neighbour, which reorienting does not undo: where
    cells overlap, renderers that walk from cell to cell and those that integrate every cell differ."""
    n = int(np.count_nonzero(folded_cells(points, merged_duplicates(points, values)[tets])))
    if not n:
        return []
    return [f"{name}: {n:,} tetrahedr{'on folds' if n == 1 else 'a fold'} over a neighbour (a tangled mesh)"]


# ------------------------------------------------------------------------------------ pyvista


def volume_from_view(
    view: _pv.DatasetView, scalars: str | None, source: str, name: str, channels: ChannelPick = None
) -> Volume:
    if view.kind == "image":
        return volume_from_grid(grid_from_view(view, scalars, source, name, channels), name)
    if wants_pick(channels):
        raise VolrenError(f"{source}: channels are read from image data (a uniform grid), not from a mesh")
    return tets_from_view(view, scalars, source, name)


def from_pyvista(
    dataset: Any, scalars: str | None = None, name: str = "dataset", channels: ChannelPick = None
) -> Volume:
    """A model volume from an in-memory pyvista (or VTK) dataset.

    Image data becomes a `UniformVolume`; anything else is cast to an unstructured grid and
    tetrahedralized into a `TetVolume`. `channels` (True or component numbers): the array's
    components as a multi-channel volume (`volren.io.channel_io`).
    """
    wrapped = _pv.as_dataset(dataset)
    if wrapped is None:
        raise VolrenError(f"{name}: expected a pyvista or VTK dataset, got {type(dataset).__name__}")
    return volume_from_view(_pv.view(wrapped), scalars, name, name, channels)
