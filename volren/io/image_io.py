"""Rendered images to files: PNG (8-bit, through Pillow) and .npy (the float image as is).

Renderers return premultiplied linear RGBA floats composited over black (DESIGN.md). An opaque
PNG composites that over a background colour, rgb + (1 - a) * bg, which is exact for
premultiplied colour; a transparent PNG stores straight colour, rgb / a, as PNG expects.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray
from PIL import Image

from volren.errors import VolrenError, file_error
from volren.io.safe_write import write_atomically


def _rgba(rgba: ArrayLike, path: Path) -> NDArray[np.float32]:
    image = np.asarray(rgba)
    if image.ndim != 3 or image.shape[2] != 4 or image.shape[0] == 0 or image.shape[1] == 0:
        raise VolrenError(f"{path}: an image must be an (H, W, 4) RGBA array, got shape {image.shape}")
    if image.dtype.kind != "f":
        raise VolrenError(f"{path}: an image must be float RGBA in [0, 1], got {image.dtype}")
    # float32 is ample for 8-bit output, and this runs on every frame the app shows.
    return np.nan_to_num(image.astype(np.float32, copy=False), nan=0.0, posinf=1.0, neginf=0.0)


def _to_8bit(values: NDArray) -> NDArray[np.uint8]:
    """Round half up to 8 bits (a value exactly between two steps goes to the brighter one)."""
    return np.floor(np.clip(values, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)


def to_png_pixels(
    rgba: ArrayLike,
    background: Sequence[float] = (0.0, 0.0, 0.0),
    transparent: bool = False,
    path: Path = Path("image"),
) -> NDArray[np.uint8]:
    """The 8-bit RGB (or straight RGBA when `transparent`) pixels `save_image` writes, and the app
    shows; C-contiguous (H, W, 3 or 4) uint8."""
    image = _rgba(rgba, path)
    rgb, alpha = image[..., :3], image[..., 3:]
    if transparent:
        a = np.clip(alpha, 0.0, 1.0)
        straight = np.divide(rgb, a, out=np.zeros_like(rgb), where=a > 0)
        return np.concatenate([_to_8bit(straight), _to_8bit(a)], axis=2)
    bg = np.asarray(background, dtype=np.float32).reshape(-1)
    if bg.size != 3 or not np.all(np.isfinite(bg)):
        raise VolrenError(f"{path}: background must be three numbers (r, g, b) in [0, 1], got {background!r}")
    return _to_8bit(rgb + (1.0 - alpha) * bg)


def save_image(
    rgba: ArrayLike,
    path: str | Path,
    background: Sequence[float] = (0.0, 0.0, 0.0),
    transparent: bool = False,
) -> None:
    """Write a premultiplied float RGBA image as PNG: opaque over `background`, or with alpha."""
    path = Path(path)
    pixels = to_png_pixels(rgba, background, transparent, path)
    try:  # RGB or RGBA from the last axis; the old file stays until the new one is complete
        write_atomically(path, lambda tmp: Image.fromarray(pixels).save(tmp, format="PNG"))
    except (OSError, ValueError) as exc:
        raise file_error(path, f"cannot write the PNG: {exc}") from None


def save_array(rgba: ArrayLike, path: str | Path) -> None:
    """Write the float32 (H, W, 4) premultiplied RGBA image itself as .npy."""
    path = Path(path)
    image = np.asarray(rgba)
    if image.ndim != 3 or image.shape[2] != 4:
        raise VolrenError(f"{path}: an image must be an (H, W, 4) RGBA array, got shape {image.shape}")

    def write(tmp: Path) -> None:
        with open(tmp, "wb") as f:
            np.save(f, image.astype(np.float32, copy=False))

    try:
        write_atomically(path, write)
    except OSError as exc:
        raise file_error(path, f"cannot write: {exc.strerror}") from None
