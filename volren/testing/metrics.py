"""DESIGN.md's error metric: RMSE over all pixels and the four premultiplied RGBA channels,
with the max abs difference and PSNR (peak 1) reported beside it."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class ImageError:
    rmse: float
    max_abs: float
    psnr: float

    def __str__(self) -> str:
        return f"RMSE {self.rmse:.5f}, max {self.max_abs:.4f}, PSNR {self.psnr:.1f} dB"


def image_error(image: NDArray, reference: NDArray) -> ImageError:
    if image.shape != reference.shape:
        raise ValueError(f"images differ in shape: {image.shape} vs {reference.shape}")
    diff = np.asarray(image, np.float64) - np.asarray(reference, np.float64)
    rmse = float(np.sqrt(np.mean(diff * diff)))
    psnr = math.inf if rmse == 0 else 20.0 * math.log10(1.0 / rmse)
    return ImageError(rmse, float(np.abs(diff).max()), psnr)
