"""Mouse gestures -> camera operations, following vtkInteractorStyleTrackballCamera (no Qt).

People who use ParaView or VTK's render windows expect these exact feels, so the factors are
VTK's: a drag across the whole viewport rotates by 200 degrees (MotionFactor 10 x 20 degrees),
a vertical right-drag over half the viewport height dollies by 1.1 ** 10, a wheel notch by
1.1 ** 2, and a middle-drag pans so that the point under the mouse at the focal depth follows it.

All deltas are in screen pixels with Qt's orientation (y grows downward). Every function returns
a new camera whose clipping range is reset on `bounds`, because the renderers take the clipping
range from our camera as is (VTK's interactor does the same through the renderer).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from volren.model.camera import Camera

#: vtkInteractorStyle's MotionFactor.
MOTION_FACTOR = 10.0
#: vtkInteractorStyle's MouseWheelMotionFactor times the 0.2 its wheel handlers apply.
WHEEL_FACTOR = 0.2 * MOTION_FACTOR
#: Qt's angleDelta for one wheel notch.
WHEEL_NOTCH = 120.0


def rotate(camera: Camera, dx: float, dy: float, width: int, height: int, bounds: Sequence[float]) -> Camera:
    """Left-drag: azimuth from the horizontal motion, elevation from the vertical, view up re-orthogonalized."""
    azimuth = -dx * 20.0 / max(width, 1) * MOTION_FACTOR
    elevation = dy * 20.0 / max(height, 1) * MOTION_FACTOR  # Qt's y points down, VTK's up
    cam = camera.azimuth(azimuth).elevation(elevation).orthogonalize_view_up()
    return cam.reset_clipping_range(bounds)


def dolly(camera: Camera, factor: float, bounds: Sequence[float]) -> Camera:
    """Move toward the focal point by `factor` (> 1 enlarges); parallel cameras zoom instead."""
    cam = camera.zoom(factor) if camera.parallel else camera.dolly(factor)
    return cam.reset_clipping_range(bounds)


def drag_dolly_factor(dy: float, height: int) -> float:
    """Right-drag: moving up (dy < 0) by half the viewport height dollies in by 1.1 ** 10."""
    return 1.1 ** (-MOTION_FACTOR * dy / max(height / 2.0, 1.0))


def wheel_dolly_factor(angle_delta: float) -> float:
    """Wheel: each notch forward (angle delta +120) dollies in by 1.1 ** 2."""
    return 1.1 ** (WHEEL_FACTOR * angle_delta / WHEEL_NOTCH)


def world_per_pixel(camera: Camera, height: int) -> float:
    """World units per screen pixel at the focal point's depth."""
    if camera.parallel:
        return 2.0 * camera.parallel_scale / max(height, 1)
    return 2.0 * camera.distance * math.tan(math.radians(camera.view_angle) / 2.0) / max(height, 1)


def pan(camera: Camera, dx: float, dy: float, height: int, bounds: Sequence[float]) -> Camera:
    """Middle-drag: the scene follows the mouse (the camera moves the other way)."""
    scale = world_per_pixel(camera, height)
    return camera.pan(-dx * scale, dy * scale).reset_clipping_range(bounds)
