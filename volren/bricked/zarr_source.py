"""One level of an OME-Zarr image as a brick source: blocks assembled from its chunks through a
bounded `ChunkCache`, brick value ranges from the ranges volren stores (so a brick the TF makes
transparent is never read), and the level of detail a view needs.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from volren.bricked.chunk_cache import ChunkCache
from volren.bricked.layout import BrickLayout
from volren.errors import VolrenError
from volren.io import ome_zarr_io
from volren.io.ome_zarr_io import LevelInfo, Multiscale
from volren.model.bricks import BrickGrid
from volren.model.camera import Camera
from volren.quality import DEFAULT_LEVEL

#: The share of the memory allowed that the chunk cache may fill: the rest is for the process
#: itself (Python, the renderer's GL driver: about 0.4 GiB) and the frame's images (measured with
#: `python -m benchmarks.scale`: 2048^3 uint16 at --memory 2GB peaked at 1.9 GiB resident).
CACHE_SHARE = 0.75
#: The quality levels that preview: with no level named they draw the coarsest level the view
#: needs (`level_for_view`); every other level draws the full resolution.
PREVIEW_QUALITIES = ("draft", "interactive")


class ZarrSource:
    """Level `level` of `image`, read a block at a time, keeping at most `CACHE_SHARE` of
    `budget` bytes (the memory allowed for the whole process) of chunks, less `reserve` bytes for
    the brick being drawn (`brick_reserve`; the cache keeps one chunk at least)."""

    def __init__(self, image: Multiscale, level: int, budget: int, reserve: int = 0) -> None:
        if not 0 <= level < len(image.levels):
            raise VolrenError(
                f"{image.path}: no level {level}; the image has levels 0 to {len(image.levels) - 1}"
            )
        self.image = image
        self.level = level
        self.info = info = image.levels[level]
        self.name = image.name
        self.dimensions = tuple(int(n) for n in info.shape[::-1])
        if min(self.dimensions) < 2:
            raise VolrenError(
                f"{image.path}: level {info.key!r} is {info.shape[::-1]}: fewer than 2 samples on an axis"
            )
        self.spacing = info.spacing
        self.origin = info.origin
        chunk = math.prod(info.chunks) * info.dtype.itemsize
        self.cache = ChunkCache(max(int(budget * CACHE_SHARE) - reserve, chunk))
        self._grids: dict[tuple[int, int], BrickGrid] = {}
        self._array = image.array(level)
        self._ranges = self._stored_ranges()
        self.value_range = self._whole_range()

    @property
    def brick(self) -> int:
        """Render bricks as large as the smallest chunk side, so that they line up with chunks."""
        return int(min(self.info.chunks))

    # ------------------------------------------------------------------------- ranges
    def _chunk_counts(self) -> tuple[int, int, int]:
        return tuple(math.ceil(n / c) for n, c in zip(self.info.shape, self.info.chunks, strict=True))  # type: ignore[return-value]

    def _stored_ranges(self) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
        """(vmin, vmax) per chunk (kz, ky, kx) from volren's metadata (+inf/-inf: no finite value)."""
        if self.image.brick_ranges is None:
            return None
        ranges = self.image.brick_ranges[self.level]
        shape = self._chunk_counts()
        vmin = np.array([np.inf if r is None else r[0] for r in ranges], dtype=np.float64).reshape(shape)
        vmax = np.array([-np.inf if r is None else r[1] for r in ranges], dtype=np.float64).reshape(shape)
        return vmin, vmax

    def _whole_range(self) -> tuple[float, float]:
        """The level's finite value range: from the stored ranges, else by reading every chunk once."""
        if self._ranges is None:
            self._ranges = self._scan_ranges()
        vmin, vmax = self._ranges
        if not np.isfinite(vmin).any():
            raise VolrenError(f"{self.image.path}: level {self.info.key!r} holds no finite values")
        return float(vmin[np.isfinite(vmin)].min()), float(vmax[np.isfinite(vmax)].max())

    def _scan_ranges(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Every chunk's range, reading the level once, a chunk at a time (an image volren did
        not write has none stored)."""
        shape = self._chunk_counts()
        vmin = np.full(shape, np.inf)
        vmax = np.full(shape, -np.inf)
        for index in np.ndindex(*shape):
            values = self._chunk(index)
            finite = values if np.issubdtype(values.dtype, np.integer) else values[np.isfinite(values)]
            if finite.size:
                vmin[index], vmax[index] = finite.min(), finite.max()
        return vmin, vmax

    def brick_grid(self, layout: BrickLayout, ghost: int) -> BrickGrid:
        """Per render brick: the range of every chunk its sub-volume (voxels and ghosts) touches
        (made once per brick size and ghost width)."""
        key = (layout.brick, ghost)
        if key not in self._grids:
            self._grids[key] = self._brick_grid(layout, ghost)
        return self._grids[key]

    def _brick_grid(self, layout: BrickLayout, ghost: int) -> BrickGrid:
        assert self._ranges is not None
        cvmin, cvmax = self._ranges
        chunks = self.info.chunks  # (z, y, x)
        vmin = np.empty(layout.shape)
        vmax = np.empty(layout.shape)
        for brick in layout.bricks():
            sel = tuple(slice(max(brick.first[a] - ghost, 0) // chunks[2 - a], (brick.end[a] + ghost) // chunks[2 - a] + 1)
                        for a in (2, 1, 0))  # fmt: skip
            vmin[brick.index] = cvmin[sel].min()
            vmax[brick.index] = cvmax[sel].max()
        return BrickGrid(vmin, vmax, np.zeros(layout.shape, dtype=bool), layout.brick, layout.dimensions,
                         layout.spacing, layout.origin)  # fmt: skip

    # --------------------------------------------------------------------------- reading
    def _chunk(self, index: tuple[int, ...]) -> NDArray:
        return self.cache.get(
            index, lambda: ome_zarr_io.read_brick(self.image, self.level, self._array, index)
        )

    def read(self, slices: tuple[slice, slice, slice]) -> NDArray:
        """The values [z, y, x] of a block, from the chunks it touches."""
        chunks = self.info.chunks
        out = np.empty(tuple(s.stop - s.start for s in slices), dtype=self.info.dtype)
        ranges = [range(s.start // c, (s.stop - 1) // c + 1) for s, c in zip(slices, chunks, strict=True)]
        for index in np.ndindex(*(len(r) for r in ranges)):
            chunk_index = tuple(r[i] for r, i in zip(ranges, index, strict=True))
            values = self._chunk(chunk_index)
            src, dst = [], []
            for s, c, k in zip(slices, chunks, chunk_index, strict=True):
                lo, hi = max(s.start, k * c), min(s.stop, (k + 1) * c)
                src.append(slice(lo - k * c, hi - k * c))
                dst.append(slice(lo - s.start, hi - s.start))
            out[tuple(dst)] = values[tuple(src)]
        return out


#: The most ghost voxels a renderer asks for on each side of a brick (the slicer's, shaded).
MAX_GHOST = 2


def brick_reserve(info: LevelInfo, copies_per_voxel: int) -> int:
    """The memory to leave beside the chunk cache for drawing one brick of a level: twice its
    voxels, ghosts included, at the values' bytes and the renderer's copies' (measured: streaming
    512^3 uint16 in 64^3 bricks with the slicer took 19 MiB besides a nearly empty cache, and
    each cached MiB 1.3 MiB resident: the brick's arrays, and what the heap keeps of the last)."""
    voxels = (int(min(info.chunks)) + 2 * MAX_GHOST) ** 3
    return 2 * voxels * (info.dtype.itemsize + copies_per_voxel)


def level_bounds(info: LevelInfo) -> tuple[float, float, float, float, float, float]:
    out: list[float] = []
    for o, h, n in zip(info.origin, info.spacing, info.shape[::-1], strict=True):
        out += [o, o + h * (n - 1)]
    return tuple(out)  # type: ignore[return-value]


def level_for_view(
    levels: Sequence[LevelInfo], camera: Camera, width: int, height: int, pixels: float = 1.0
) -> int:
    """The coarsest level whose voxels look no larger than `pixels` pixels where the volume comes
    nearest to the camera (0 when the camera is inside it or even level 0 looks coarser).

    Why the nearest point: a level fine enough there is fine enough everywhere in the view, so
    the image shows no voxel larger than a pixel.
    """
    if camera.parallel:
        world_per_pixel = 2.0 * camera.parallel_scale / height
    else:
        b = np.asarray(level_bounds(levels[0]))
        eye = np.asarray(camera.position, dtype=np.float64)
        nearest = np.clip(eye, b[0::2], b[1::2])
        distance = max(float(np.linalg.norm(eye - nearest)), camera.clipping_range[0])
        world_per_pixel = 2.0 * distance * math.tan(math.radians(camera.view_angle) / 2.0) / height
    for level in range(len(levels) - 1, -1, -1):
        if max(levels[level].spacing) <= pixels * world_per_pixel:
            return level
    return 0


def level_at_quality(levels: Sequence[LevelInfo], camera: Camera, width: int, height: int,
                     quality: str = DEFAULT_LEVEL) -> int:  # fmt: skip
    """The level a frame at `quality` draws when none is named: the full resolution (0), except
    for a preview (`PREVIEW_QUALITIES`), which draws the coarsest level the view needs.

    Why not the view's level at every quality: a 2x2x2 block mean spreads a feature thinner than
    the coarser voxel over its neighbours, which can drop it below the TF's threshold however
    small the pixels are (a one-voxel bright tube vanishes); no pixel-size rule keeps it.
    """
    return level_for_view(levels, camera, width, height) if quality in PREVIEW_QUALITIES else 0
