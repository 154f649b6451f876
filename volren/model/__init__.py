"""The data model: volumes, transfer functions, camera, render settings, scenes.

Pure numpy and the standard library: nothing here imports VTK, PyVista, moderngl or Qt, so the
model can be used and tested anywhere. The one exception is `model.preintegration` (imported on
its own, not from here), whose table kernels use numba.
"""

from volren.model.camera import Camera
from volren.model.settings import BlendMode, RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TFWidget, TransferFunction, TransferFunction2D
from volren.model.volume import TetVolume, UniformVolume, Volume, VolumeKind

__all__ = [
    "BlendMode",
    "Camera",
    "RenderSettings",
    "TetVolume",
    "TFWidget",
    "TransferFunction",
    "TransferFunction1D",
    "TransferFunction2D",
    "UniformVolume",
    "Volume",
    "VolumeKind",
]
