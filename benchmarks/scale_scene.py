"""The scene `python -m benchmarks.scale` draws at every size: the procedural volume's TF, camera and
settings (the slicer's defaults, early termination off, so that every brick is drawn as the
whole render would be)."""

from __future__ import annotations

from volren.model.camera import Camera
from volren.model.settings import RenderSettings
from volren.model.transfer_function import TransferFunction1D


def scale_tf() -> TransferFunction1D:
    """Transparent below 20000 (the empty space outside the sphere and the low values), opaque
    toward the peaks; the opacity unit distance is a fixed world length, so every size draws the
    same picture."""
    return TransferFunction1D([[0, 0.2, 0.4, 1.0], [60000, 1.0, 0.9, 0.3]],
                              [[0, 0.0], [20000, 0.0], [40000, 0.3], [60000, 0.8]], 0.05)  # fmt: skip


def scale_settings(renderer: str = "slicer") -> RenderSettings:
    return RenderSettings(options={"early_termination": False} if renderer == "slicer" else {})


def scale_camera(image) -> Camera:
    from volren.bricked.zarr_source import level_bounds

    return Camera.orbit(level_bounds(image.levels[0]), 30, 20)
