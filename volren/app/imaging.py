"""Renderer output -> displayable pixels (no Qt).

Renderers return premultiplied linear RGBA composited over black (DESIGN.md). Over another
background colour b the displayed colour is rgb + (1 - a) b, which needs no division because the
colour is already premultiplied. No gamma is applied: VTK and ParaView show their framebuffer
values as they are, and the app should look like them.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray


def composite_rgb8(rgba: NDArray[np.floating], background: Sequence[float] = (0.0, 0.0, 0.0)) -> NDArray[np.uint8]:
    """(H, W, 4) premultiplied float RGBA -> C-contiguous (H, W, 3) uint8 RGB over `background`."""
    if rgba.ndim != 3 or rgba.shape[2] != 4:
        raise ValueError(f"expected an (H, W, 4) RGBA image, got shape {rgba.shape}")
    rgb = rgba[..., :3].astype(np.float32, copy=False)
    bg = np.asarray(background, dtype=np.float32).reshape(1, 1, 3)
    if np.any(bg):
        alpha = np.clip(rgba[..., 3:4].astype(np.float32, copy=False), 0.0, 1.0)
        rgb = rgb + (1.0 - alpha) * bg
    out = np.clip(rgb * 255.0 + 0.5, 0.0, 255.0)
    out = np.nan_to_num(out, nan=0.0)
    return np.ascontiguousarray(out.astype(np.uint8))


def preview_size(width: int, height: int, scale: float) -> tuple[int, int]:
    """The size of a reduced-cost frame: each side times `scale` (0.5 renders a quarter of the pixels)."""
    return max(1, round(width * scale)), max(1, round(height * scale))


def adaptive_preview_scale(
    ms_per_pixel: float | None,
    full_pixels: int,
    budget_ms: float = 50.0,
    max_scale: float = 0.5,
    min_scale: float = 0.1,
) -> float:
    """The side scale of preview frames that keeps one within `budget_ms`.

    Cost is taken as proportional to the pixel count (what ray casters do), measured from the
    renderer's last frame. Fast renderers get `max_scale` (a quarter of the pixels); slow ones
    (the exact reference renderer takes seconds per full frame) get coarser previews, down to
    `min_scale`, so dragging still answers.
    """
    if not ms_per_pixel or ms_per_pixel <= 0 or full_pixels <= 0:
        return max_scale
    scale = (budget_ms / (ms_per_pixel * full_pixels)) ** 0.5
    return float(min(max_scale, max(min_scale, scale)))
