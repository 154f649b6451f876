"""Closed-form oracles shared by renderer tests: the conformance kit's own (`volren.testing`), so
the tests and the kit measure against one implementation of each formula."""

from __future__ import annotations

import numpy as np

from volren.testing.metrics import image_error
from volren.testing.oracles import box_path_lengths, homogeneous_image

__all__ = ["box_path_lengths", "homogeneous_image", "rmse"]


def rmse(a: np.ndarray, b: np.ndarray) -> float:
    return image_error(np.asarray(a, float), np.asarray(b, float)).rmse
