"""One frame of a bricked volume, sort-last: brick by brick in front-to-back order, each drawn by
the renderer into a layer over its own part of every ray (`Region`), composited with "over".

Why this equals the whole-volume render: the renderer samples every ray at the whole render's
points and draws only the pieces whose owner point lies in the brick (neighbours never share
one); the ghost voxels it asks for (`ghost_voxels`) give it the neighbours' values near a face;
and the k-d order puts the bricks in the order every ray meets them.

Bricks the TF makes transparent are never read: the value range of the brick and of its
neighbours (which the ghost voxels come from) bounds every value it can draw.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from volren.bricked.composite import over
from volren.bricked.layout import BrickLayout, Index3
from volren.bricked.source import BrickSource, has_finite
from volren.bricked.visibility import front_to_back
from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.transfer_function_2d import TransferFunction
from volren.model.volume import UniformVolume
from volren.renderers.base import FrameStats, ProgressCallback, Renderer, render_frame


@dataclass(frozen=True)
class BrickedFrame:
    """What a bricked frame did and cost."""

    bricks: int
    drawn: int
    transparent: int
    ghost: int
    read_ms: float
    render_ms: float
    composite_ms: float
    total_ms: float


def brick_layout(source: BrickSource, brick: int) -> BrickLayout:
    return BrickLayout(
        tuple(source.dimensions),
        tuple(source.spacing),
        tuple(source.origin),  # type: ignore[arg-type]
        tuple(source.value_range),
        int(brick),
    )  # type: ignore[arg-type]


def visible_bricks(source: BrickSource, layout: BrickLayout, tf, ghost: int) -> NDArray[np.bool_]:
    """Per brick (bz, by, bx): may it draw anything under `tf`? (the range of its sub-volume)"""
    grid = source.brick_grid(layout, ghost)
    if grid is None:
        return np.ones(layout.shape, dtype=bool)
    return grid.visible(tf)


@dataclass
class RunCost:
    """Time spent on a run of bricks, in ms, and the bricks drawn."""

    read_ms: float = 0.0
    render_ms: float = 0.0
    composite_ms: float = 0.0
    drawn: int = 0


def check_draws_bricks(renderer: Renderer) -> None:
    support = renderer.capabilities.kinds.get("uniform")
    if support is None or not support.regions:
        name = getattr(renderer, "name", type(renderer).__name__)
        raise VolrenError(
            f"renderer {name} does not draw bricks; bricked volumes need one that does (reference, slicer)"
        )


def draw_run(
    renderer: Renderer,
    source: BrickSource,
    layout: BrickLayout,
    tf: TransferFunction,
    camera: Camera,
    image: NDArray[np.float64],
    ghost: int,
    run: list[Index3],
    cost: RunCost,
    progress: Callable[[], None] | None = None,
) -> None:
    """Draw the bricks of `run` (front to back, all visible) into `image` (H, W, 4, float64),
    each composited under what is there. `progress` is called after each brick."""
    height, width = image.shape[:2]
    try:
        for index in run:
            t0 = time.perf_counter()
            brick = layout.brick_at(index)
            slices = layout.voxel_slices(brick, ghost)
            values = np.asarray(source.read(slices))
            t1 = time.perf_counter()
            cost.read_ms += (t1 - t0) * 1000.0
            if has_finite(values):
                sub = UniformVolume(
                    values, layout.spacing, layout.sub_origin(slices), name=f"{source.name} brick {index}"
                )
                region = layout.region(brick)
                renderer.set_volume(sub)
                renderer.set_transfer_function(tf)
                renderer.set_region(region)  # type: ignore[attr-defined]
                layer, _ = render_frame(renderer, camera, width, height)
                t2 = time.perf_counter()
                # the layer is empty outside the brick's projection: composite only there
                x0, y0, x1, y1 = region.pixel_rect(camera, width, height)
                over(image[y0:y1, x0:x1], layer[y0:y1, x0:x1], out=image[y0:y1, x0:x1])
                cost.render_ms += (t2 - t1) * 1000.0
                cost.composite_ms += (time.perf_counter() - t2) * 1000.0
                cost.drawn += 1
            if progress is not None:
                progress()
    finally:
        renderer.set_region(None)  # type: ignore[attr-defined]


def render_bricked(
    renderer: Renderer,
    source: BrickSource,
    tf: TransferFunction,
    camera: Camera,
    width: int,
    height: int,
    brick: int = 64,
    progress: ProgressCallback | None = None,
) -> tuple[NDArray[np.float32], BrickedFrame]:
    """The frame of the whole `source` through `renderer` (its settings already set) with `tf`,
    drawn brick by brick. The renderer's volume, TF and region are replaced; the region is
    cleared afterwards."""
    check_draws_bricks(renderer)
    start = time.perf_counter()
    layout = brick_layout(source, brick)
    ghost = int(renderer.ghost_voxels(layout.spacing, camera, width, height))  # type: ignore[attr-defined]
    visible = visible_bricks(source, layout, tf, ghost)
    run = [index for index in front_to_back(layout, camera) if visible[index]]
    image = np.zeros((height, width, 4), dtype=np.float64)
    cost = RunCost()
    done = [0]

    def step() -> None:
        done[0] += 1
        if progress is not None:
            progress(done[0] / max(len(run), 1))

    draw_run(renderer, source, layout, tf, camera, image, ghost, run, cost, step)
    if progress is not None and not run:
        progress(1.0)
    total = (time.perf_counter() - start) * 1000.0
    stats = BrickedFrame(layout.n_bricks, cost.drawn, int(np.count_nonzero(~visible)), ghost, cost.read_ms,
                         cost.render_ms, cost.composite_ms, total)  # fmt: skip
    return image.astype(np.float32), stats


def render_streamed(
    renderer: Renderer,
    source: BrickSource,
    tf: TransferFunction,
    camera: Camera,
    width: int,
    height: int,
    progress: ProgressCallback | None = None,
) -> tuple[NDArray[np.float32], FrameStats]:
    """A frame of `source` in bricks as large as its chunks (`source.brick`), with what it did as
    the FrameStats every frame has (bricks, times, and the chunk cache's counters)."""
    image, frame = render_bricked(renderer, source, tf, camera, width, height, source.brick, progress)  # type: ignore[attr-defined]
    counters = {"bricks": frame.bricks, "bricks_drawn": frame.drawn, "bricks_transparent": frame.transparent,
                "read_ms": frame.read_ms, "composite_ms": frame.composite_ms}  # fmt: skip
    cache = getattr(source, "cache", None)
    if cache is not None:
        counters.update(cache_misses=cache.stats.misses, cache_hits=cache.stats.hits,
                        cache_peak_bytes=cache.stats.peak_bytes)  # fmt: skip
    return image, FrameStats(frame.total_ms, width, height, counters)
