"""Closed-form oracles shared by renderer tests."""

from __future__ import annotations

import numpy as np

from volren.model.camera import Camera


def box_path_lengths(camera: Camera, width: int, height: int, bounds) -> np.ndarray:
    """Length of each pixel-centre ray inside the axis-aligned box `bounds` (slab method)."""
    origins, directions = camera.pixel_rays(width, height)
    lo = np.array(bounds[0::2], dtype=float)
    hi = np.array(bounds[1::2], dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = (lo - origins) / directions
        t2 = (hi - origins) / directions
    t_near = np.nanmax(np.minimum(t1, t2), axis=-1)
    t_far = np.nanmin(np.maximum(t1, t2), axis=-1)
    return np.clip(t_far - np.maximum(t_near, 0.0), 0.0, None)


def homogeneous_image(lengths: np.ndarray, rgb, opacity: float, unit_distance: float) -> np.ndarray:
    """Premultiplied RGBA of a constant medium: alpha = 1 - (1 - a)^(L / d), colour = c alpha."""
    alpha = 1.0 - (1.0 - opacity) ** (lengths / unit_distance)
    return np.concatenate([alpha[..., None] * np.asarray(rgb, float), alpha[..., None]], axis=-1)


def rmse(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((np.asarray(a, float) - np.asarray(b, float)) ** 2)))
