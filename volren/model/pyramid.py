"""A multiresolution pyramid of a uniform volume, as OME-Zarr stores it: each level the 2x2x2
block means of the one below, and the value range of every brick (chunk) of every level.

Why block means (not `model.downsample`'s vertex-centred filter): OME-Zarr places voxels by a
scale and a translation per level, with voxel centres; a 2x2x2 mean sits at the centre of its
block, half a fine voxel in from the block's first sample, which the translation says exactly.
An odd last sample along an axis has no partner and is left out of the coarser level (as
dask's `coarsen(trim_excess=True)`), so the coarser bounds lie inside the finer ones.

The brick ranges let a renderer skip a brick that the TF makes transparent without reading it.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError

#: Bricks of 64^3 samples: 512 KiB of uint16, small enough to stream, large enough to render.
DEFAULT_CHUNK = 64
#: Bricks from 2^3 samples (a coarser level needs 2 a side) to 1024^3 (8 GiB of float64 means).
MIN_CHUNK, MAX_CHUNK = 2, 1024


def block_mean(values: NDArray) -> NDArray:
    """The 2x2x2 block means (odd last samples left out), in the input's type: rounded to the
    nearest integer for integer data (so uint16 stays uint16), NaN where a block holds one."""
    nz, ny, nx = (n - n % 2 for n in values.shape)
    blocks = values[:nz, :ny, :nx].astype(np.float64).reshape(nz // 2, 2, ny // 2, 2, nx // 2, 2)
    means = blocks.mean(axis=(1, 3, 5))
    if np.issubdtype(values.dtype, np.integer):
        info = np.iinfo(values.dtype)
        return np.clip(np.rint(means), info.min, info.max).astype(values.dtype)
    return means.astype(values.dtype)


def default_levels(shape: tuple[int, ...], chunk: int) -> int:
    """Levels until the coarsest fits in one brick (or an axis would drop below 2 samples)."""
    levels, dims = 1, list(shape)
    while max(dims) > chunk and min(dims) >= 4:
        dims = [n // 2 for n in dims]
        levels += 1
    return levels


def max_levels(shape: tuple[int, ...]) -> int:
    """The most levels `shape` has (`level_shapes`): each halves it while every axis keeps 2 samples."""
    levels, dims = 1, list(shape)
    while min(dims) >= 4:
        dims = [n // 2 for n in dims]
        levels += 1
    return levels


def level_shapes(shape: tuple[int, ...], levels: int) -> list[tuple[int, ...]]:
    """The (z, y, x) shape of each of `levels` levels, the full resolution first: each coarser one
    half the one before, rounded down (odd last samples left out)."""
    if levels < 1:
        raise VolrenError(f"a pyramid needs at least one level, got {levels}")
    shapes = [tuple(int(n) for n in shape)]
    for index in range(1, levels):
        if min(shapes[-1]) < 4:
            raise VolrenError(f"level {index} would have fewer than 2 samples along an axis (level {index - 1} is "
                              f"{'x'.join(map(str, shapes[-1][::-1]))}); ask for fewer levels")  # fmt: skip
        shapes.append(tuple(n // 2 for n in shapes[-1]))
    return shapes


def coarser_placement(
    spacing: Sequence[float], origin: Sequence[float]
) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """(spacing, origin) of the level above one placed at `spacing`, `origin`: twice the spacing,
    and the first block mean at the centre of its block, half a fine voxel in."""
    return (tuple(2.0 * h for h in spacing),
            tuple(o + 0.5 * h for o, h in zip(origin, spacing, strict=True)))  # fmt: skip


def brick_slices(
    shape: tuple[int, ...], chunk: int
) -> Iterator[tuple[tuple[int, int, int], tuple[slice, ...]]]:
    """(brick index (kz, ky, kx), the brick's slices) over a level, in C order of the brick grid."""
    counts = [math.ceil(n / chunk) for n in shape]
    for kz in range(counts[0]):
        for ky in range(counts[1]):
            for kx in range(counts[2]):
                index = (kz, ky, kx)
                yield (
                    index,
                    tuple(
                        slice(k * chunk, min((k + 1) * chunk, n)) for k, n in zip(index, shape, strict=True)
                    ),
                )


def value_range(brick: NDArray) -> tuple[float, float] | None:
    """(min, max) of a brick's finite values; None when it has none."""
    if np.issubdtype(brick.dtype, np.integer):
        return float(brick.min()), float(brick.max())
    finite = brick[np.isfinite(brick)]
    return (float(finite.min()), float(finite.max())) if finite.size else None
