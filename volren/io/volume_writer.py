"""Model volumes -> files (.vti for grids, .vtu for meshes, or any format PyVista writes)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from volren.errors import VolrenError, file_error
from volren.model.volume import TetVolume, UniformVolume, Volume

SCALARS_NAME = "values"


def to_pyvista(volume: Volume):
    """The volume as a pyvista ImageData or UnstructuredGrid with point scalars `values`."""
    import pyvista as pv

    if isinstance(volume, UniformVolume):
        grid = pv.ImageData(dimensions=volume.dimensions, spacing=volume.spacing, origin=volume.origin)
        grid.point_data[SCALARS_NAME] = volume.values.reshape(-1)
    elif isinstance(volume, TetVolume):
        cells = np.hstack([np.full((len(volume.tets), 1), 4), volume.tets]).reshape(-1)
        grid = pv.UnstructuredGrid(cells, np.full(len(volume.tets), pv.CellType.TETRA), volume.points)
        grid.point_data[SCALARS_NAME] = volume.values
    else:
        raise VolrenError(f"cannot convert {type(volume).__name__} to a dataset")
    grid.set_active_scalars(SCALARS_NAME)
    return grid


def save_volume(volume: Volume, path: str | Path) -> None:
    """Write `volume`; the format follows the suffix (.vti/.vtk for grids, .vtu/.vtk for meshes)."""
    path = Path(path)
    try:
        to_pyvista(volume).save(path)
    except (ValueError, OSError, TypeError) as exc:
        raise file_error(path, f"cannot write: {' '.join(str(exc).split())}") from None
