"""The only place this renderer imports VTK (so what it depends on is visible in one file)."""

from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray, vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkCommand, vtkPoints, vtkUnsignedCharArray
from vtkmodules.vtkCommonDataModel import (
    VTK_TETRA,
    vtkCellArray,
    vtkImageData,
    vtkPiecewiseFunction,
    vtkPlane,
    vtkPlaneCollection,
    vtkUnstructuredGrid,
)
from vtkmodules.vtkCommonExecutionModel import vtkTrivialProducer
from vtkmodules.vtkRenderingCore import (
    vtkColorTransferFunction,
    vtkRenderer,
    vtkRenderWindow,
    vtkVolume,
    vtkVolumeProperty,
)
from vtkmodules.vtkRenderingVolume import (
    vtkFixedPointVolumeRayCastMapper,
    vtkMultiVolume,
    vtkProjectedTetrahedraMapper,
    vtkUnstructuredGridLinearRayIntegrator,
    vtkUnstructuredGridPreIntegration,
    vtkUnstructuredGridVolumeRayCastMapper,
    vtkUnstructuredGridVolumeZSweepMapper,
)
from vtkmodules.vtkRenderingVolumeOpenGL2 import (
    vtkOpenGLGPUVolumeRayCastMapper,
    vtkOpenGLProjectedTetrahedraMapper,
    vtkSmartVolumeMapper,
)

try:  # the offscreen window class; absent in VTK builds without EGL
    from vtkmodules.vtkRenderingOpenGL2 import vtkEGLRenderWindow
except ImportError:  # pragma: no cover - depends on the VTK build
    vtkEGLRenderWindow = None  # type: ignore[misc,assignment]

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401,E402  (registers the OpenGL factories)

__all__ = [
    "vtkPlane",
    "vtkPlaneCollection",
    "VTK_TETRA",
    "numpy_to_vtk",
    "numpy_to_vtkIdTypeArray",
    "vtk_to_numpy",
    "vtkCellArray",
    "vtkColorTransferFunction",
    "vtkCommand",
    "vtkEGLRenderWindow",
    "vtkFixedPointVolumeRayCastMapper",
    "vtkImageData",
    "vtkMultiVolume",
    "vtkOpenGLGPUVolumeRayCastMapper",
    "vtkOpenGLProjectedTetrahedraMapper",
    "vtkPiecewiseFunction",
    "vtkPoints",
    "vtkProjectedTetrahedraMapper",
    "vtkRenderWindow",
    "vtkRenderer",
    "vtkSmartVolumeMapper",
    "vtkTrivialProducer",
    "vtkUnsignedCharArray",
    "vtkUnstructuredGrid",
    "vtkUnstructuredGridLinearRayIntegrator",
    "vtkUnstructuredGridPreIntegration",
    "vtkUnstructuredGridVolumeRayCastMapper",
    "vtkUnstructuredGridVolumeZSweepMapper",
    "vtkVolume",
    "vtkVolumeProperty",
]
