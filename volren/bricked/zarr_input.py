"""How `volren render` and `volren.render` draw an OME-Zarr image: which level, and whether it is
read whole into memory or streamed brick by brick within the memory allowed.

- A renderer that draws bricks (regions) gets the full resolution (level 0) at quality default,
  high and exact, and at draft and interactive (previews) the level of detail the view needs: the
  coarsest level whose voxels look no larger than a pixel (`--level` overrides both). A level that
  fits in the memory allowed, counting the renderer's own copies of it (`RENDERER_COPY_BYTES`: a
  uint16 level drawn by the slicer takes 16x its bytes), is read whole (one frame, fastest); a
  larger one is streamed: bricks in visibility order through a chunk cache of that size,
  transparent bricks never read.
- Any other renderer gets the finest level that fits in the memory allowed with its copies, read
  whole, with a one-line warning when that is not the full resolution.

The scene is set up (default TF, checks) on the coarsest level, which is small; the camera is
placed on the full resolution's bounds, so it does not move with the level drawn.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from volren.bricked.zarr_source import CACHE_SHARE, ZarrSource, brick_reserve, level_at_quality, level_bounds
from volren.errors import VolrenError
from volren.io import ome_zarr_io
from volren.io.ome_zarr_io import Multiscale
from volren.model.camera import Camera
from volren.model.volume import UniformVolume
from volren.quality import DEFAULT_LEVEL


@dataclass(frozen=True)
class ZarrFrame:
    """What one frame draws: a level read whole (`volume`) or streamed (`source`)."""

    level: int
    volume: UniformVolume | None = None
    source: ZarrSource | None = None

    def describe(self) -> str:
        how = "streamed" if self.source is not None else "in memory"
        return f"level {self.level} {how}"


#: Bytes a voxel that each renderer's own copies of a level read whole take at their peak, beyond
#: the level's values: what reading a level whole costs on top of its bytes. Measured with
#: tracemalloc and peak resident memory, drawing a 256^3 (slicer, reference) or 128^3 uint16 level
#: (2026-12-06): slicer 12 (its float32 texture, normalised through a float64 copy), 30 shaded or
#: with a 2D TF (gradients too); objectorder 18; reference 8 (float64); shearwarp 7; raycast 5;
#: vtk 2, 4 shaded.
RENDERER_COPY_BYTES = {
    "slicer": 30,
    "objectorder": 18,
    "reference": 8,
    "shearwarp": 8,
    "raycast": 6,
    "vtk": 4,
}
#: A renderer not measured is taken to copy as much as the one that copies most.
MOST_COPY_BYTES = max(RENDERER_COPY_BYTES.values())


def renderer_copy_bytes(renderer: str) -> int:
    """`RENDERER_COPY_BYTES` of `renderer`; the most for one not measured, or `auto` not yet chosen."""
    return RENDERER_COPY_BYTES.get(renderer, MOST_COPY_BYTES)


def finest_level_read_whole(image: Multiscale, budget: int, renderer: str) -> int | None:
    """The finest level `renderer` draws read whole within `budget` bytes, its copies of the level
    counted (`renderer_copy_bytes`); None when not even the coarsest fits. The level `volren
    render` draws with a renderer that does not stream bricks, and `volren view` refines up to
    (the app reads every level whole)."""
    return ome_zarr_io.finest_level_within(image, budget, renderer_copy_bytes(renderer))


def least_memory(image: Multiscale) -> int:
    """The least memory allowed in which `image` draws with any renderer: its coarsest level read
    whole (what the scene is set up on) and, streamed, a chunk of any level in the chunk cache
    (a cache smaller than a chunk keeps nothing, and the memory asked for would mean nothing)."""
    chunk = max(math.prod(level.chunks) * level.dtype.itemsize for level in image.levels)
    return max(ome_zarr_io.level_bytes(image.levels[-1]), math.ceil(chunk / CACHE_SHARE))


class ZarrInput:
    """An opened OME-Zarr image and the memory allowed for it (default 8 GiB; `memory_name`: how
    the caller named it, for the error when it is too little)."""

    def __init__(self, path: str | Path, memory: int | None = None, memory_name: str = "memory") -> None:
        self.path = str(path)
        self.name = self.path.rstrip("/").rsplit("/", 1)[-1] if ome_zarr_io.is_url(path) else Path(path).name
        self.image: Multiscale = ome_zarr_io.open_multiscale(path)
        if memory is not None and memory < least_memory(self.image):
            raise VolrenError(f"{self.path}: {memory_name} {ome_zarr_io.human_size(memory)} is too little; this image "
                              f"needs at least {ome_zarr_io.human_size(least_memory(self.image))} (its coarsest level "
                              "read whole, and a chunk in the chunk cache)")  # fmt: skip
        self.budget = memory if memory is not None else ome_zarr_io.MAX_IN_MEMORY_BYTES
        self.memory_name = memory_name
        self.bounds = level_bounds(self.image.levels[0])

    def stand_in(self) -> UniformVolume:
        """The coarsest level, read whole: what the scene is set up on."""
        return ome_zarr_io.load_level(self.path, len(self.image.levels) - 1, name=self.name)

    def check_level(self, level: int) -> None:
        if not 0 <= level < len(self.image.levels):
            raise VolrenError(
                f"{self.path}: no level {level}; the image has levels 0 to {len(self.image.levels) - 1}"
            )

    def _finest_drawn_within_budget(self, renderer: str, copies: int) -> int:
        """For a renderer that does not stream bricks: the finest level that it draws within the
        memory allowed, counting its copies (`finest_level_said`); one line when none does."""
        level = ome_zarr_io.finest_level_said(self.image, self.budget, self.name,
                                              f" (renderer {renderer} does not stream bricks)", copies)  # fmt: skip
        if level is None:
            drawn = ome_zarr_io.human_size(ome_zarr_io.level_bytes(self.image.levels[-1], copies))
            raise VolrenError(f"{self.path}: {self.memory_name} {ome_zarr_io.human_size(self.budget)} is too little for "
                              f"renderer {renderer}, which does not stream bricks: it takes {drawn} to draw even the "
                              "coarsest level")  # fmt: skip
        return level

    def frame(self, renderer: str, camera: Camera, width: int, height: int, level: int | None = None,
              quality: str = DEFAULT_LEVEL) -> ZarrFrame:  # fmt: skip
        """How `renderer` draws this image for `camera` at `width` x `height` at `quality` (which
        picks the level when `level` is None: `level_at_quality`)."""
        from volren.renderers.registry import registry

        support = registry.capabilities(renderer).kinds.get("uniform")
        if level is not None:
            self.check_level(level)
        copies = renderer_copy_bytes(renderer)
        if support is None or not support.regions:
            if level is None:
                level = self._finest_drawn_within_budget(renderer, copies)
            return ZarrFrame(
                level, volume=ome_zarr_io.load_level(self.path, level, name=self.name, memory=self.budget)
            )
        if level is None:
            level = level_at_quality(self.image.levels, camera, width, height, quality)
        drawn = ome_zarr_io.level_bytes(self.image.levels[level], copies)
        if drawn <= min(self.budget, ome_zarr_io.MAX_IN_MEMORY_BYTES):
            return ZarrFrame(
                level, volume=ome_zarr_io.load_level(self.path, level, name=self.name, memory=self.budget)
            )
        reserve = brick_reserve(self.image.levels[level], copies)
        return ZarrFrame(level, source=ZarrSource(self.image, level, self.budget, reserve))
