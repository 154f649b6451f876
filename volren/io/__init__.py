"""Files to model objects and back.

Volumes come in through PyVista/VTK readers (every VTK import is in `volren.io._pv`); transfer
functions, scenes and images are plain JSON, NumPy and Pillow. Every failure a file can cause is
a `VolrenError` with one line naming the file and the problem.
"""

from volren.io.dataset import from_pyvista
from volren.io.formats import SUPPORTED as SUPPORTED_VOLUME_FORMATS
from volren.io.image_io import save_array, save_image
from volren.io.scene_io import load_scene, save_scene, scene_time_series
from volren.io.tf_io import load_transfer_function, save_transfer_function
from volren.io.volume_io import load_volume
from volren.io.volume_writer import save_volume, to_pyvista

__all__ = [
    "SUPPORTED_VOLUME_FORMATS",
    "from_pyvista",
    "load_scene",
    "load_transfer_function",
    "load_volume",
    "save_array",
    "save_image",
    "save_scene",
    "save_transfer_function",
    "save_volume",
    "scene_time_series",
    "to_pyvista",
]
