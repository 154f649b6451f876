"""A coarser copy of a uniform volume, for draft renders and previews.

Why this filter: samples are vertex-centred (the grid's bounds run from the first sample to the
last), so a 2:1 reduction smooths with the [1, 2, 1] / 4 kernel along each axis (the linear
B-spline's restriction, which removes what the coarse grid cannot hold without shifting
anything; the border samples are kept, as if the data went on linearly, so that linear data
stays exactly linear) and then samples the smoothed field at ceil((n - 1) / 2) + 1 evenly spaced points
that keep the bounds exactly. A plain stride would alias thin features away; a block average
would shift the grid by half a voxel. Non-finite values stay transparent: a coarse sample whose
filter touches one is NaN (conservative: the transparent region grows by at most one coarse cell).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError
from volren.model.volume import UniformVolume

#: Reduction factors `downsample` accepts (each a power of two: repeated 2:1 reductions).
FACTORS = (1, 2, 4, 8)


def _smooth(values: NDArray[np.float32], axis: int) -> NDArray[np.float32]:
    """[1, 2, 1] / 4 along `axis`; the two border samples are kept (linear extension: 2 v0 - v1 beyond v0)."""
    moved = np.moveaxis(values, axis, 0)
    out = np.empty_like(moved)
    out[1:-1] = 0.5 * moved[1:-1] + 0.25 * (moved[:-2] + moved[2:])
    out[0] = moved[0]
    out[-1] = moved[-1]
    return np.moveaxis(out, 0, axis)


def _resample(values: NDArray[np.float32], axis: int, count: int) -> NDArray[np.float32]:
    """`count` samples evenly spaced from the first sample to the last along `axis`, linear in between."""
    n = values.shape[axis]
    if count == n:
        return values
    x = np.arange(count) * ((n - 1) / (count - 1))
    i0 = np.minimum(x.astype(np.int64), n - 2)
    w = (x - i0).astype(np.float32)
    shape = [1] * values.ndim
    shape[axis] = count
    w = w.reshape(shape)
    return values.take(i0, axis=axis) * (1.0 - w) + values.take(i0 + 1, axis=axis) * w


def _halve(values: NDArray[np.float32]) -> NDArray[np.float32]:
    for axis in range(3):
        n = values.shape[axis]
        if n > 2:
            values = _resample(_smooth(values, axis), axis, math.ceil((n - 1) / 2) + 1)
    return values


def downsample(volume: UniformVolume, factor: int) -> UniformVolume:
    """`volume` reduced `factor`:1 along each axis (an axis keeps at least 2 samples), with the
    same bounds; `factor` 1 returns `volume` itself."""
    if isinstance(factor, bool) or not isinstance(factor, int) or factor not in FACTORS:
        raise VolrenError(
            f"{volume.name}: downsampling factor must be one of {', '.join(map(str, FACTORS))}, got {factor!r}"
        )
    if factor == 1:
        return volume
    values = np.asarray(volume.values, np.float32)
    if volume.nonfinite_count:
        values = np.where(np.isfinite(values), values, np.float32(np.nan))
    for _ in range(int(math.log2(factor))):
        values = _halve(values)
    nz, ny, nx = volume.values.shape
    counts = values.shape[::-1]
    spacing = tuple(
        s * (n - 1) / (m - 1) for s, n, m in zip(volume.spacing, (nx, ny, nz), counts, strict=True)
    )
    return UniformVolume(np.ascontiguousarray(values), spacing=spacing, origin=volume.origin,
                         name=f"{volume.name} (1/{factor})")  # fmt: skip
