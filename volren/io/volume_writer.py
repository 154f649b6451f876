"""Model volumes -> files (.vti for grids, .vtu for meshes, or any format PyVista writes)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from volren.errors import VolrenError, file_error
from volren.io import _pv, reader_messages
from volren.io.safe_write import write_atomically
from volren.model.volume import TetVolume, UniformVolume, Volume

SCALARS_NAME = "values"


def to_pyvista(volume: Volume) -> Any:
    """The volume as a pyvista ImageData or UnstructuredGrid with point scalars `values`."""
    if isinstance(volume, UniformVolume):
        return _pv.image_data(volume.values, volume.spacing, volume.origin, SCALARS_NAME)
    if isinstance(volume, TetVolume):
        return _pv.tet_grid(volume.points, volume.tets, volume.values, SCALARS_NAME)
    raise VolrenError(f"cannot convert {type(volume).__name__} to a dataset")


def save_volume(volume: Volume, path: str | Path) -> None:
    """Write `volume`; the format follows the suffix (.vti/.vtk for grids, .vtu/.vtk for meshes)."""
    path = Path(path)
    dataset = to_pyvista(volume)

    def write(tmp: Path) -> None:
        problem = reader_messages.problem(_pv.save(dataset, tmp), path)
        if problem:
            raise file_error(path, f"cannot write: {problem}")

    try:  # the old file stays until the new one is complete
        write_atomically(path, write)
    except (ValueError, OSError, TypeError) as exc:
        raise file_error(path, f"cannot write: {' '.join(str(exc).split())}") from None
