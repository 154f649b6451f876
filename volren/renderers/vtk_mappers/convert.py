"""Model volumes as VTK datasets (the scalars are shared with numpy where the dtype allows)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from volren.model.volume import TetVolume, UniformVolume
from volren.renderers.vtk_mappers._vtk import (
    VTK_TETRA,
    numpy_to_vtk,
    numpy_to_vtkIdTypeArray,
    vtkCellArray,
    vtkImageData,
    vtkPoints,
    vtkUnstructuredGrid,
)

SCALARS_NAME = "values"


def _scalars(values: NDArray):
    array = numpy_to_vtk(np.ascontiguousarray(values.reshape(-1)), deep=True)
    array.SetName(SCALARS_NAME)
    return array


def image_data(volume: UniformVolume, values: NDArray) -> vtkImageData:
    """vtkImageData with `values` (same layout as volume.values, x fastest) as point scalars."""
    image = vtkImageData()
    image.SetDimensions(*volume.dimensions)
    image.SetSpacing(*volume.spacing)
    image.SetOrigin(*volume.origin)
    image.GetPointData().SetScalars(_scalars(values))
    return image


def unstructured_grid(volume: TetVolume, values: NDArray) -> vtkUnstructuredGrid:
    """vtkUnstructuredGrid of VTK_TETRA cells with `values` as point scalars."""
    grid = vtkUnstructuredGrid()
    points = numpy_to_vtk(volume.points, deep=True)
    vtk_points = vtkPoints()
    vtk_points.SetData(points)
    grid.SetPoints(vtk_points)
    n = len(volume.tets)
    offsets = numpy_to_vtkIdTypeArray(np.arange(0, 4 * n + 1, 4, dtype=np.int64), deep=True)
    connectivity = numpy_to_vtkIdTypeArray(volume.tets.reshape(-1).astype(np.int64), deep=True)
    cells = vtkCellArray()
    cells.SetData(offsets, connectivity)
    grid.SetCells(VTK_TETRA, cells)
    grid.GetPointData().SetScalars(_scalars(values))
    return grid
