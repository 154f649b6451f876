"""Sizes of the frames the app asks for (no Qt).

Frames become displayable pixels through `volren.io.image_io.to_png_pixels`, the same conversion
screenshots use: rgb + (1 - a) * background, no gamma (VTK and ParaView show their framebuffer
values as they are, and the app should look like them).
"""

from __future__ import annotations


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
