"""The class of a 1D transfer function: `smooth`, `sharp` or `band`, what quality levels are chosen by.

Why classes: what a quality level needs differs by TF, and one configuration for every scene pays
the sharp TFs' price on the smooth ones. Measured on the shared grids (2026-12-02): objectorder's
post-classified step 0.5 is within VTK's default's RMSE on every smooth TF but 1.64x over it on
ironProt's opaque one, its pre-integrated step 0.5 within on every sharp TF but 1.83x over on
aneurism's smooth one (docs/bench/quality.md).

A 1D TF is `smooth` or `sharp` (`tf_sharpness`: how steeply its optical depth changes across the
data's value range), and a sharp one is a `band` TF when it is visible on a narrow part of that
range only (`tf_visible_fraction`). Other TFs (2D) have no class.
"""

from __future__ import annotations

import math
from enum import Enum

import numpy as np

from volren.model.transfer_function import MAX_OPACITY, TransferFunction1D

#: A 1D TF is `sharp` when its optical depth per opacity unit distance changes by at least this much across
#: the data's value range at its steepest (`tf_sharpness`). The shared scenes' TFs lie far either side:
#: smooth 0.3-5.2, spiky and opaque 235-1760 (the quality benchmark prints each scene's; the bundled
#: samples' 2.1, 12 and 51), so the class does not hinge on the exact value; 30 is about the shared
#: scenes' geometric middle.
SHARP_TF = 30.0
#: A sharp 1D TF is a `band` TF when it is visible (opacity > 0) on less than this fraction of the
#: data's value range: narrow peaks of opacity around a few values (thin shells), not steps up to a
#: solid body. The shared scenes lie far either side: spiky 0.027-0.047; opaque 0.32-0.90, the
#: samples 0.20-1 (the quality benchmark prints each scene's); 0.1 is about their geometric middle.
#: Why a class of its own: VTK's post-classified default misses most of a thin peak (its RMSE on
#: bonsai's spiky TF is 3.6x that on the opaque one), so coarser pre-integrated settings reach its
#: error there and not on the steps (shearwarp's pre-integrated oversampling 1, measured 2026-12-03:
#: within it on every spiky TF, up to 0.9x; 1.55-1.9x over it on three of the four opaque TFs and
#: 1.42x on phantom_ct's).
BAND_TF = 0.1
#: Classes kept by (opacity points, value range): the app asks for a TF's class 7 times per settings change
#: (0.7 ms each, 5 ms of the GUI thread at every step of a clip plane's drag).
_KEPT_CLASSES = 256


class TFClass(Enum):
    """How a 1D TF's opacity changes over the data's values (see the module docstring)."""

    SMOOTH = "smooth"
    SHARP = "sharp"
    BAND = "band"

    @classmethod
    def of_features(cls, sharpness: float, visible: float) -> TFClass:
        """The class of a `tf_sharpness` and a `tf_visible_fraction`."""
        if sharpness < SHARP_TF:
            return cls.SMOOTH
        return cls.BAND if visible < BAND_TF else cls.SHARP

    @classmethod
    def of(cls, tf: object, value_range: tuple[float, float]) -> TFClass | None:
        """The class of a 1D TF over data spanning `value_range`; None for other TFs. Kept by the TF's
        opacity points, all that it depends on: an edited TF is classed again."""
        if not isinstance(tf, TransferFunction1D):
            return None
        key = (tf.opacity_points.tobytes(), float(value_range[0]), float(value_range[1]))
        found = _classes.get(key)
        if found is None:
            sharpness = tf_sharpness(tf, value_range)
            visible = tf_visible_fraction(tf, value_range)
            assert sharpness is not None and visible is not None  # a 1D TF's
            found = cls.of_features(sharpness, visible)
            if len(_classes) >= _KEPT_CLASSES:
                _classes.clear()
            _classes[key] = found
        return found


_classes: dict[tuple[bytes, float, float], TFClass] = {}


def tf_sharpness(tf: object, value_range: tuple[float, float]) -> float | None:
    """The steepest change of a 1D TF's optical depth, -ln(1 - a), over its opacity points, times the
    data's value span (inf for a step); None for a TF that is not 1D."""
    if not isinstance(tf, TransferFunction1D):
        return None
    points = tf.opacity_points
    span = float(value_range[1]) - float(value_range[0])
    if len(points) < 2 or not span > 0.0:
        return 0.0
    depth = -np.log1p(-np.minimum(np.clip(points[:, 1], 0.0, 1.0), MAX_OPACITY))
    rise = np.abs(np.diff(depth))
    run = np.diff(points[:, 0])
    steps = (run <= 0.0) & (rise > 0.0)
    if steps.any():
        return math.inf
    slopes = np.where(run > 0.0, rise / np.where(run > 0.0, run, 1.0), 0.0)
    return float(slopes.max()) * span


def tf_visible_fraction(tf: object, value_range: tuple[float, float]) -> float | None:
    """The fraction of the data's value range on which a 1D TF's opacity is positive (4097 evenly
    spaced values; 1 or 0 for constant data); None for a TF that is not 1D."""
    if not isinstance(tf, TransferFunction1D):
        return None
    lo, hi = float(value_range[0]), float(value_range[1])
    values = np.linspace(lo, hi, 4097) if hi > lo else np.array([lo])
    return float(np.mean(tf.sample(values)[1] > 0.0))
