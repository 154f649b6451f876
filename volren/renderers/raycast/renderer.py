"""The `raycast` renderer: image-order ray casting of uniform grids on the CPU (C or numba).

Why: with no GPU, a ray per pixel marched front to back is the cheapest way to a ray caster's image
when cells project to about a pixel: it pays per sample, stops a ray once it is opaque, and skips
empty space per brick (`march`, `occupancy`). Post-classified samples follow DESIGN.md's optical
model exactly as the slicer and objectorder do (the midpoint rule on planes shared by all pixels,
neighbouring pixels half a step apart): raycast and objectorder agree to float precision at the
same step. Pre-integrated segments run from plane to plane, objectorder's from sample to
sample, and the slicer's between its slices, so the three differ by the discretisation (up to 0.04
max on a sharp TF at step 0.5).
Maximum, minimum and average march
the same samples (and, for the extremes, every grid-plane crossing). No shading: the capabilities say
so, and `auto` picks another renderer for shaded scenes.
"""

from __future__ import annotations

import hashlib
import math
import time
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from typing import Any, ClassVar, Literal

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError
from volren.kernels.image_stride import STRIDE_RULE
from volren.kernels.pixel_phases import pixel_phases
from volren.model import BlendMode, Camera, TransferFunction1D, TransferFunction2D, UniformVolume
from volren.model.bricks import BrickGrid
from volren.model.channels import ChannelTransferFunction
from volren.model.labels import LabelClasses, LabelTransferFunction, cell_classes
from volren.model.settings import check_step
from volren.model.transfer_function import MAX_OPACITY
from volren.model.volume import spanning
from volren.renderers.base import (
    Accuracy,
    Capabilities,
    KindSupport,
    OptionSpec,
    ProgressCallback,
    QualityLevel,
    RendererBase,
)
from volren.renderers.raycast import march_native
from volren.renderers.raycast.march_inputs import (
    COUNTS,
    TILE,
    ChannelClassification,
    Classification,
    EmptyBricks,
    Gradients2D,
    LabelClassification,
    PixelView,
    Table2D,
    gradients,
    interval_kinds,
)
from volren.renderers.raycast.occupancy import empty_distance
from volren.renderers.raycast.step_cache import remembered_step
from volren.renderers.raycast.step_choice import largest_step_within, sample_size

OFFSET_MODES = ("interleaved", "midpoint")
OPTIONS: tuple[OptionSpec, ...] = (
    OptionSpec("brick_size", 4, "int", "cells per brick edge for empty-space skipping", low=1, high=64),
    OptionSpec(
        "empty_space_skipping", True, "bool", "skip bricks the TF makes transparent (the image is the same)"
    ),
    OptionSpec(
        "termination_alpha",
        0.999,
        "float",
        "opacity at which a ray stops (1 never stops early)",
        low=0.5,
        high=1.0,
    ),
    OptionSpec(
        "depth_offsets",
        "interleaved",
        "choice",
        "where each pixel's segments start: 'interleaved' (phase 0 and 1/2 of a step on a checkerboard) or "
        "'midpoint' (all on the same planes); the jitter setting gives seeded random phases",
        choices=OFFSET_MODES,
    ),
    OptionSpec("jitter_seed", 0, "int", "seed of the random phases", low=0, high=2**63 - 1),
    OptionSpec("table_size", 256, "int", "entries per axis of the pre-integration table", low=16, high=4096),
    OptionSpec(
        "classification_table", 4096, "int", "entries of the post-classification table", low=16, high=65536
    ),
    OptionSpec(
        "image_stride",
        1,
        "int",
        "1: a ray through every pixel; 2 to 64 (a power of two): adaptive refinement, rays every "
        "`image_stride` pixels first, more only where neighbouring rays differ by more than "
        "refine_tolerance or at silhouettes, the rest interpolated (faster on smooth images; features "
        "thinner than the stride between rays that agree are missed; composite only)",
        rule=STRIDE_RULE,
    ),
    OptionSpec(
        "refine_tolerance",
        0.02,
        "float",
        "with image_stride > 1: the largest difference in any premultiplied RGBA channel between a block's "
        "corner rays that is interpolated instead of cast",
        low=0.0,
        high=1.0,
    ),
    OptionSpec(
        "table_2d",
        512,
        "int",
        "entries of a 2D TF's table along value, half as many along gradient magnitude (a 2D TF's "
        "previews while it is dragged take 128: the table is sampled again at every step)",
        low=16,
        high=4096,
    ),
    OptionSpec(
        "target_error",
        0.0,
        "float",
        "0: march at the settings' step; above 0 (composite only): the largest step of step x 2^(-k/8), "
        "k = 0..24, whose RMSE over the image's root mean square (0.01: 1 %), estimated on the rays of a "
        "~64x64 image of the view against a march 16x finer than step, is at most this; chosen at the "
        "first frame of a TF and volume",
        low=0.0,
        high=1.0,
    ),
)
#: The clip planes of a view that clips nothing.
NO_PLANES = np.zeros((0, 4), np.float64)
#: Tiles per progress call.
TILES_PER_CALL = 1024
#: Pixels handed to a thread at a time when adaptive refinement asks for scattered pixels.
PIXEL_CHUNK = 16
#: The march kernels' arguments before the pixels and outputs: the values, `EmptyBricks`, `PixelView`,
#: `Classification` and the termination opacity.
MarchArgs = tuple[NDArray[Any], EmptyBricks, PixelView, Classification, float]


#: The kernels a frame runs: (every pixel in tiles, listed pixels).
Kernels = tuple[Callable[..., None], Callable[..., None]]
#: Which march draws a frame: a 1D TF's, a 2D TF's, a label volume's (`march_labels`) or a
#: multi-channel volume's (`march_channels`).
MarchKind = Literal["1d", "2d", "labels", "channels"]


def _kernels(march: MarchKind, values: NDArray[Any]) -> tuple[Kernels, bool]:
    """(kernels, whether they are numba's): the 1D TF's, the 2D TF's, or the label or multi-channel
    volume's march, in C where they build (`march_native`) else numba's (`march`, `march2d`,
    `march_mixed`), looked up when a frame runs. numba's modules are imported only here: a frame the
    C march draws does not pay numba's import and first call."""
    native = march_native.kernels(values, march)
    if native is not None:
        return native, False
    if march in ("labels", "channels"):
        from volren.renderers.raycast import march_mixed

        return (march_mixed.march_mixed, march_mixed.march_mixed_pixels), True
    if march == "2d":
        from volren.renderers.raycast import march2d

        return (march2d.march2d, march2d.march2d_pixels), True
    from volren.renderers.raycast import march as march_1d

    return (march_1d.march, march_1d.march_pixels), True


@contextmanager
def _chunks(numba_kernels: bool, size: int) -> Iterator[None]:
    """numba's parallel chunk size set to `size` meanwhile where numba's kernels draw (the C march
    takes tiles from a shared counter of its own)."""
    if not numba_kernels:
        yield
        return
    from volren.kernels.row_blocks import parallel_chunk_size

    with parallel_chunk_size(size):
        yield


#: A 2D TF's table entries along value in previews while it is dragged (`table_2d`): sampling the
#: TF at 512 x 256 points took most of a 160x160 preview's time; at 128 previews take 1.5-4.5x less
#: time, off by RMSE 0.00002-0.004 where spikes are narrower than an entry (python -m
#: benchmarks.tf2d_drag). The still frame after the drag uses the full table.
TF_DRAG_TABLE_2D = 128
#: The most opacity a 2D TF's table drops on any ray: extinctions below this over the volume's
#: diagonal are drawn as none. Why: a Gaussian widget's opacity never reaches 0 (1e-9 of its peak
#: six widths away), so an exact table leaves no brick empty and no sample's gradient unread. A
#: ray crosses at most the diagonal D, so it loses at most 1 - exp(-tau D) <= this much opacity
#: and premultiplied colour (400x below an 8-bit step), wherever the dropped entries lie.
NEGLIGIBLE_OPACITY = 1e-5


def _counters(totals: NDArray[np.int64]) -> dict[str, float]:
    """A frame's counters from its march's totals (`march.COUNTS`): samples taken, distance jumps,
    segments skipped in empty bricks, rays terminated early."""
    names = {"skipped": "segments_skipped", "terminated": "rays_terminated"}
    return {names.get(name, name): float(total) for name, total in zip(COUNTS, totals, strict=True)}


def _visible_under_table(
    grid: BrickGrid, table: NDArray[np.float32], lo: float, hi: float
) -> NDArray[np.bool_]:
    """The bricks a ray must sample under a 2D TF's table: those with extinction at any gradient
    magnitude for a value in their range (widened by one entry either side: the table interpolates
    between entries)."""
    nv = table.shape[1]
    seen = np.concatenate([[0], np.cumsum(table[..., 3].max(axis=0) > 0.0)])
    scale = (nv - 1) / (hi - lo)
    first = np.clip(np.floor((grid.vmin - lo) * scale) - 1, 0, nv - 1).astype(np.int64)
    last = np.clip(np.ceil((grid.vmax - lo) * scale) + 1, 0, nv - 1).astype(np.int64)
    return (seen[last + 1] - seen[first] > 0) & ~grid.empty


#: The most memory a label volume's classification tables take together (`classification_table`
#: entries per class, fewer where many classes would exceed it; at least 16).
LABEL_TABLES_BYTES = 256 * 2**20
#: Above this many label classes, bricks are classified by the union of the visible classes (one
#: pass over the labels) instead of class by class (a pass each).
MAX_CLASSES_PER_BRICK = 16


def _visible_classes(
    grid: BrickGrid, labels: NDArray[Any], classes: LabelClasses, pad: float
) -> NDArray[np.bool_]:
    """The bricks a label volume's rays must sample: those where a class present at some corner of
    the brick's cells has opacity in the brick's value range (widened by `pad`). Past
    `MAX_CLASSES_PER_BRICK` classes, the bricks holding any visible label where any class has opacity."""
    class_of = classes.lookup[labels]
    visible = np.zeros(grid.shape, dtype=bool)
    if len(classes.tfs) > MAX_CLASSES_PER_BRICK:
        present = BrickGrid.from_array((class_of >= 0).view(np.uint8), grid.brick).vmax > 0
        for tf in classes.tfs:
            visible |= grid.visible(tf, pad=pad)
        return visible & present
    for c, tf in enumerate(classes.tfs):
        shown = grid.visible(tf, pad=pad)
        if shown.any():
            visible |= shown & (BrickGrid.from_array((class_of == c).view(np.uint8), grid.brick).vmax > 0)
    return visible


def _visible_channels(grid: BrickGrid, values: NDArray[Any], drawn: list[int], tf: ChannelTransferFunction,
                      pads: tuple[float, ...]) -> NDArray[np.bool_]:  # fmt: skip
    """The bricks a multi-channel volume's rays must sample: those where some drawn channel's TF has
    opacity over that channel's range in the brick (widened by its table's `pads`)."""
    visible = np.zeros(grid.shape, dtype=bool)
    for row, c in enumerate(drawn):
        visible |= BrickGrid.from_array(values[row], grid.brick).visible(tf.tfs[c], pad=pads[row])
    return visible


def _march_listed(
    args: tuple, pixels: NDArray[np.int64], march: MarchKind = "1d"
) -> tuple[NDArray[np.float32], NDArray[np.int64]]:
    """(premultiplied RGBA (n, 4), counts (n, 4): `march.COUNTS`) of the listed pixels' rays (`march_pixels`)."""
    rgba = np.empty((len(pixels), 4), np.float32)
    counts = np.zeros((len(pixels), len(COUNTS)), np.int64)
    (_, listed), numba_kernels = _kernels(march, args[0])
    with _chunks(numba_kernels, PIXEL_CHUNK):
        listed(*args, np.ascontiguousarray(pixels, dtype=np.int64), rgba, counts)
    return rgba, counts


class RaycastRenderer(RendererBase):
    """Image-order ray casting on uniform grids: composite (post-classified or pre-integrated),
    maximum, minimum, average."""

    name: ClassVar[str] = "raycast"
    capabilities: ClassVar[Capabilities] = Capabilities(
        kinds={
            "uniform": KindSupport(
                tf_dims=frozenset({1, 2}),  # 2D: composite, post-classified (`march2d`)
                preintegration=True,
                blend_modes=frozenset(BlendMode),
                accuracy=Accuracy(rmse=0.02, position_px=0.05),
                clip_region=True,
                clip_cap=True,
                labels=True,  # composite, post-classified (`march_labels`)
                channels=True,  # composite, post-classified (`march_channels`)
            )
        },
        backend="cpu",
        summary="image-order ray casting (C with AVX2 where it builds, else numba): brick skipping with distance "
        "jumps, early ray termination, "
        "adaptive image refinement, the step chosen from an error target",
        # a TF drag's previews march at the level's coarsest step instead of estimating the error per edit,
        # and sample a 2D TF's table at fewer entries (it is sampled again at every edit)
        tf_drag_options={"target_error": 0.0, "table_2d": TF_DRAG_TABLE_2D},
        still_frame_options={"image_stride": 1},  # the app refines images in previews only
        quality=(
            QualityLevel("step 1", step=1.0, preintegration=False),
            QualityLevel("step 1, pre-integrated", step=1.0, preintegration=True),
            QualityLevel("step 0.5 (default)", step=0.5, preintegration=False),
            QualityLevel("step 0.5, pre-integrated", step=0.5, preintegration=True),
            QualityLevel("step 0.25", step=0.25, preintegration=False),
            QualityLevel("step 0.25, pre-integrated", step=0.25, preintegration=True),
            QualityLevel(
                "step 1, refine 8/0.02",
                step=1.0,
                preintegration=False,
                options={"image_stride": 8, "refine_tolerance": 0.02},
            ),
            QualityLevel(
                "step 0.5, refine 4/0.01",
                step=0.5,
                preintegration=False,
                options={"image_stride": 4, "refine_tolerance": 0.01},
            ),
            # sharp TFs (thin shells, opaque surfaces): a fine step, most rays interpolated, small bricks
            QualityLevel(
                "step 0.25, refine 8/0.02",
                step=0.25,
                preintegration=False,
                options={"image_stride": 8, "refine_tolerance": 0.02},
            ),
            QualityLevel(
                "step 0.25, refine 8/0.02, bricks 2",
                step=0.25,
                preintegration=False,
                options={"image_stride": 8, "refine_tolerance": 0.02, "brick_size": 2},
            ),
            # the step chosen per TF and volume from an error estimate (`step_choice`), 2 to 0.25
            QualityLevel(
                "error 1 %, refine 8/0.02",
                step=2.0,
                preintegration=False,
                options={"target_error": 0.01, "image_stride": 8, "refine_tolerance": 0.02},
            ),
            QualityLevel(
                "error 0.4 %, refine 4/0.01",
                step=2.0,
                preintegration=False,
                options={"target_error": 0.004, "image_stride": 4, "refine_tolerance": 0.01},
            ),
            QualityLevel("error 0.2 %", step=2.0, preintegration=False, options={"target_error": 0.002}),
        ),
    )
    options: ClassVar[tuple[OptionSpec, ...]] = OPTIONS

    def __init__(self) -> None:
        super().__init__()
        self._values: NDArray[np.uint8] | NDArray[np.float32] | None = None
        self._grid: tuple[tuple[int, int], BrickGrid] | None = None
        self._empty: tuple[tuple, NDArray[np.int8]] | None = None
        self._phases: tuple[tuple, NDArray[np.float64]] | None = None
        self._step: tuple[tuple, tuple[float, float]] | None = (
            None  # (TF and settings, (step, its estimated error))
        )
        self._gradients: Gradients2D | None = None  # the grid points' gradients, for 2D TFs
        self._cells: tuple[tuple, NDArray[np.int16]] | None = None  # a label volume's `cell_classes`
        self._channel_values: tuple[tuple, NDArray[Any]] | None = None  # the drawn channels, as marched
        self._tables: tuple[tuple, NDArray[np.float64]] | None = None  # a label or channel scene's tables
        self._table2d: tuple[tuple, NDArray[np.float32], NDArray[np.int8], str] | None = (
            None  # (TF version, table, kinds, digest)
        )

    def _volume_changed(self) -> None:
        volume = self.volume
        assert isinstance(volume, UniformVolume)
        raw = volume.values  # 8-bit volumes stay 8-bit (a quarter of the memory, measured as fast)
        self._values = march_native.padded(raw if raw.dtype == np.uint8 else raw.astype(np.float32))
        self._grid = None
        self._empty = None
        self._step = None
        self._gradients = None
        self._cells = None
        self._channel_values = None
        self._tables = None

    def release(self) -> None:
        self._values = self._grid = self._empty = self._phases = None
        self._cells = self._channel_values = self._tables = None
        super().release()

    def _empty_bricks(self, key: tuple, brick: int, reach: int, skipping: bool,
                      visible: Callable[[BrickGrid], NDArray[np.bool_]]) -> NDArray[np.int8]:  # fmt: skip
        """Each brick's distance to the nearest brick to sample (`occupancy`), kept while `key` (what
        decides which bricks are visible: the TF's opacity or table, the brick size, the reach) stays,
        so that a colour edit, a camera move and the step search reuse it. `visible(grid)`: the bricks
        of `brick` cells (their ranges widened by `reach` cells) a ray must sample; every brick
        without skipping."""
        if self._empty is not None and self._empty[0] == key:
            return self._empty[1]
        volume = self.volume
        assert isinstance(volume, UniformVolume)
        if self._grid is None or self._grid[0] != (brick, reach):
            self._grid = ((brick, reach), BrickGrid.from_volume(volume, brick, reach))
        grid = self._grid[1]
        distance = empty_distance(visible(grid) if skipping else np.ones(grid.shape, dtype=bool))
        self._empty = (key, distance)
        return distance

    def _render(
        self, camera: Camera, width: int, height: int, progress: ProgressCallback | None
    ) -> tuple[NDArray[np.float32], Mapping[str, float]]:
        volume = self.volume
        tf = self.transfer_function
        assert isinstance(volume, UniformVolume)
        assert isinstance(
            tf, TransferFunction1D | TransferFunction2D | LabelTransferFunction | ChannelTransferFunction
        )
        assert self._values is not None
        settings = self.settings
        opts = self.opts
        check_step(settings.step, volume.bounds, volume.characteristic_length)
        h = float(settings.step * volume.characteristic_length)
        mode = settings.blend_mode
        mode_key = "random" if settings.jitter else opts["depth_offsets"]
        key = (mode_key, width, height, opts["jitter_seed"])
        if self._phases is None or self._phases[0] != key:
            self._phases = (key, pixel_phases(mode_key, width, height, opts["jitter_seed"]))
        phases = self._phases[1]
        inv = np.linalg.inv(camera.projection_matrix(width / height) @ camera.view_matrix())
        near, far = camera.clipping_range
        origin = np.asarray(volume.origin, dtype=np.float64)
        spacing = np.asarray(volume.spacing, dtype=np.float64)
        view_dir = np.asarray(camera.direction, dtype=np.float64)
        planes = settings.clip.half_spaces_in_grid(origin, spacing)
        view = PixelView(inv, width, height, origin, spacing, view_dir, float(far - near), phases, planes)
        if isinstance(tf, TransferFunction2D):  # composite, post-classified (the capabilities)
            if settings.clip.caps:
                raise VolrenError("raycast: cut faces (clip caps) need a 1D transfer function")
            return self._render_2d(tf, h, opts, view, mode_key, progress)
        if isinstance(tf, LabelTransferFunction):
            return self._render_labels(tf, h, opts, view, mode_key, progress)
        if isinstance(tf, ChannelTransferFunction):
            return self._render_channels(tf, h, opts, view, mode_key, progress)
        if mode != BlendMode.COMPOSITE:
            return self._project(tf, mode, view, h)
        pre = bool(settings.preintegration)
        key = (tf.color_points.tobytes(), tf.opacity_points.tobytes(), tf.opacity_unit_distance, h, pre,
               *(opts[k] for k in ("target_error", "table_size", "classification_table", "termination_alpha",
                                   "brick_size", "empty_space_skipping")))  # fmt: skip
        h, chosen = self._chosen_step(key, lambda step, at: self._march_args(tf, step, pre, opts, at), "1d", h,
                                      opts, view, mode_key)  # fmt: skip
        args = self._march_args(tf, h, pre, opts, view)
        return self._marched(args, args[1].distance, "1d", view, opts, progress, chosen)

    def _marched(self, args: tuple, empty: NDArray[np.int8], march: MarchKind, view: PixelView, opts: Mapping[str, Any],
                 progress: ProgressCallback | None,
                 chosen: Mapping[str, float]) -> tuple[NDArray[np.float32], Mapping[str, float]]:  # fmt: skip
        """The frame the march's arguments draw (1D or 2D TF): a ray through every pixel, or adaptively
        refined at `image_stride`; its counters with the bricks and the step's choice (`chosen`)."""
        width, height, stride = view.width, view.height, int(opts["image_stride"])
        if stride > 1:
            image, totals, rays = self._refined(
                args, width, height, stride, opts["refine_tolerance"], progress, march
            )
        else:
            image, totals = self._every_pixel(args, width, height, progress, march)
            rays = width * height
        return image, {**_counters(totals), "rays_cast": float(rays),
                       "bricks_empty": float(np.count_nonzero(empty)), "bricks": float(empty.size), **chosen}  # fmt: skip

    def _march_args(self, tf: TransferFunction1D, h: float, pre: bool, opts: Mapping[str, Any],
                    view: PixelView) -> MarchArgs:  # fmt: skip
        """The march kernels' arguments at step h (world units) for the view: brick distances,
        classification or pre-integration table, termination opacity."""
        volume = self.volume
        assert isinstance(volume, UniformVolume)
        brick = int(opts["brick_size"])
        # a pre-integrated segment starting in a cell ends at most this many cells beyond it
        reach = int(math.ceil(h / min(volume.spacing) - 1e-9)) if pre else 0
        vlo, vhi = volume.value_range
        tlo, thi = tf.value_range
        lo, hi = min(vlo, tlo), max(vhi, thi)
        if not (math.isfinite(lo) and math.isfinite(hi)):
            lo, hi = tlo, thi
        lo, hi = spanning(lo, hi)
        table = np.zeros((2, 2, 4), np.float32)
        post = np.zeros((2, 4))
        cap = self.settings.clip.caps
        n = int(opts["table_size"] if pre else opts["classification_table"])
        if pre:
            from volren.model.preintegration import preintegrate  # numba's: imported when a frame needs it

            table = preintegrate(tf, n, step=h, value_range=(lo, hi))
        if not pre or cap:  # pre-integrated, the cut faces read it at the same entries
            rgb, a = tf.sample(np.linspace(lo, hi, n))
            alpha = -np.expm1(h / tf.opacity_unit_distance * np.log1p(-np.minimum(a, MAX_OPACITY)))
            post = np.ascontiguousarray(np.concatenate([rgb, alpha[:, None]], axis=1), dtype=np.float64)
        table = table.view()  # read-only, as a cached table is: numba compiles a kernel once per
        table.flags.writeable = False  # combination of writable and read-only arrays
        classes = Classification(pre, post, table, float(h), float(lo), float((n - 1) / (hi - lo)), cap)
        term = float(opts["termination_alpha"]) if opts["termination_alpha"] < 1.0 else 2.0
        # classified over ranges widened by one entry of the table, which interpolates between the
        # entries either side of a value
        pad, skipping = (hi - lo) / (n - 1), bool(opts["empty_space_skipping"])
        empty = self._empty_bricks((tf.opacity_points.tobytes(), brick, skipping, reach, pad), brick, reach, skipping,
                                   lambda grid: grid.visible(tf, pad=pad))  # fmt: skip
        assert self._values is not None
        return self._values, EmptyBricks(empty, brick), view, classes, term

    def _chosen_step(self, key: tuple, args_at: Callable[[float, PixelView], tuple], march: MarchKind, coarsest: float,
                     opts: Mapping[str, Any], view: PixelView,
                     phase_mode: str) -> tuple[float, dict[str, float]]:  # fmt: skip
        """(step, the frame's counters that report it): `coarsest` where no error is targeted, else
        `_step_within`'s step for the TF and settings `key` (the march's arguments at a step and view:
        `args_at`)."""
        if not opts["target_error"] > 0:
            return coarsest, {}
        start = time.perf_counter()
        h, estimate = self._step_within(key, args_at, march, coarsest, opts, view, phase_mode)
        length = self.volume.characteristic_length  # type: ignore[union-attr]
        return h, {"step": h / length, "step_relative_error": estimate,
                   "step_choice_ms": 1000.0 * (time.perf_counter() - start)}  # fmt: skip

    def _step_within(self, key: tuple, args_at: Callable[[float, PixelView], tuple], march: MarchKind,
                     coarsest: float, opts: Mapping[str, Any], view: PixelView,
                     phase_mode: str) -> tuple[float, float]:  # fmt: skip
        """(step, its estimated relative RMSE) for the target_error option (`step_choice`), estimated on
        every ray of a ~64x64 image of this frame's view and kept while the TF, the volume and the
        settings (`key`) stay (a camera move keeps it: the step must not change from frame to frame of
        a rotation). The search marches what the frame marches: a 1D or 2D TF, or labels."""
        if self._step is None or self._step[0] != key:
            width, height = sample_size(view.width, view.height)
            phases = pixel_phases(phase_mode, width, height, opts["jitter_seed"])
            # the step serves the TF and the data, whatever is clipped: a plane's drag keeps it
            sampled = view._replace(width=width, height=height, phases=phases, planes=NO_PLANES)
            pixels = np.arange(width * height, dtype=np.int64)

            def image_at(h: float) -> NDArray[np.float32]:
                return _march_listed(args_at(h, sampled), pixels, march)[0]

            def search() -> tuple[float, float]:
                return largest_step_within(image_at, coarsest, opts["target_error"])

            # the view (`step_cache`), and which march searches (C and numba agree to float rounding only)
            assert self._values is not None
            native = march_native.kernels(self._values, march) is not None
            scene = (key, phase_mode, opts["jitter_seed"], sampled[:7], native)
            self._step = (key, remembered_step(self._values, scene, search))
        return self._step[1]

    def _render_2d(self, tf: TransferFunction2D, h: float, opts: Mapping[str, Any], view: PixelView, phase_mode: str,
                   progress: ProgressCallback | None) -> tuple[NDArray[np.float32], Mapping[str, float]]:  # fmt: skip
        """A frame with a 2D TF (`march2d`): at the settings' step, or the error-targeted one (searched
        on the 2D march as for 1D TFs), every pixel or adaptively refined."""
        _, _, digest = self._table_2d(tf, int(opts["table_2d"]))
        key = ("2d", digest, tf.value_range, tf.gradient_range, h,
               *(opts[k] for k in ("target_error", "termination_alpha", "brick_size", "empty_space_skipping")))  # fmt: skip
        h, chosen = self._chosen_step(key, lambda step, at: self._march2d_args(tf, step, opts, at), "2d", h, opts,
                                      view, phase_mode)  # fmt: skip
        args = self._march2d_args(tf, h, opts, view)
        return self._marched(args, args[2].distance, "2d", view, opts, progress, chosen)

    def _render_labels(self, tf: LabelTransferFunction, h: float, opts: Mapping[str, Any], view: PixelView,
                       phase_mode: str,
                       progress: ProgressCallback | None) -> tuple[NDArray[np.float32], Mapping[str, float]]:  # fmt: skip
        """A frame of a label volume (`march_labels`): composite and post-classified (the capabilities),
        at the settings' step or the error-targeted one, every pixel or adaptively refined."""
        settings = self.settings
        if settings.blend_mode != BlendMode.COMPOSITE:
            raise VolrenError(
                f"raycast: label volumes are drawn composite only, not with {settings.blend_mode}"
            )
        if settings.clip.caps:
            raise VolrenError("raycast: cut faces (clip caps) are not drawn on label volumes")
        labels = self.volume.labels  # type: ignore[union-attr]
        assert labels is not None  # `render` refuses a label TF on a volume without labels
        key = ("labels", tf.digest(), labels.digest, h,
               *(opts[k] for k in ("target_error", "classification_table", "termination_alpha", "brick_size",
                                   "empty_space_skipping")))  # fmt: skip
        h, chosen = self._chosen_step(key, lambda step, at: self._label_args(tf, step, opts, at), "labels", h, opts,
                                      view, phase_mode)  # fmt: skip
        args = self._label_args(tf, h, opts, view)
        return self._marched(args, args[1].distance, "labels", view, opts, progress, chosen)

    def _label_args(
        self, tf: LabelTransferFunction, h: float, opts: Mapping[str, Any], view: PixelView
    ) -> tuple:
        """`march_labels`' arguments at step h (world units) for the view: the values, the bricks where
        some visible class has opacity in the brick's range, each class's table, the termination opacity."""
        volume = self.volume
        assert isinstance(volume, UniformVolume) and volume.labels is not None and self._values is not None
        labels = volume.labels
        classes = tf.classes(labels.max_label)
        key = (labels.digest, classes.lookup.tobytes())
        if self._cells is None or self._cells[0] != key:
            self._cells = (key, cell_classes(labels.values, classes.lookup, labels.boundary))
        vlo, vhi = volume.value_range
        tlo, thi = tf.value_range
        lo, hi = spanning(min(vlo, tlo), max(vhi, thi))
        # many classes share the tables' memory: fewer entries each
        n = max(
            16, min(int(opts["classification_table"]), LABEL_TABLES_BYTES // (32 * max(len(classes.tfs), 1)))
        )
        table_key = ("labels", tf.state(), h, n, lo, hi)
        if self._tables is None or self._tables[0] != table_key:  # a table per class: kept while they stay
            post = np.zeros((max(len(classes.tfs), 1), n, 4))
            for c, class_tf in enumerate(classes.tfs):
                rgb, a = class_tf.sample(np.linspace(lo, hi, n))
                post[c, :, :3] = rgb
                post[c, :, 3] = -np.expm1(
                    h / class_tf.opacity_unit_distance * np.log1p(-np.minimum(a, MAX_OPACITY))
                )
            self._tables = (table_key, post)
        post = self._tables[1]
        brick, skipping = int(opts["brick_size"]), bool(opts["empty_space_skipping"])
        pad = (hi - lo) / (n - 1)
        empty = self._empty_bricks(("labels", tf.digest(), labels.digest, brick, skipping, pad), brick, 0, skipping,
                                   lambda grid: _visible_classes(grid, labels.values, classes, pad))  # fmt: skip
        table = LabelClassification(labels.values, classes.lookup, self._cells[1], post, float(h), float(lo),
                                    float((n - 1) / (hi - lo)))  # fmt: skip
        term = float(opts["termination_alpha"]) if opts["termination_alpha"] < 1.0 else 2.0
        return self._values, EmptyBricks(empty, brick), view, table, term

    def _render_channels(self, tf: ChannelTransferFunction, h: float, opts: Mapping[str, Any], view: PixelView,
                         phase_mode: str,
                         progress: ProgressCallback | None) -> tuple[NDArray[np.float32], Mapping[str, float]]:  # fmt: skip
        """A frame of a multi-channel volume (`march_channels`): composite and post-classified (the
        capabilities), at the settings' step or the error-targeted one, every pixel or refined."""
        settings = self.settings
        if settings.blend_mode != BlendMode.COMPOSITE:
            raise VolrenError(f"raycast: channels are mixed composite only, not with {settings.blend_mode}")
        if settings.clip.caps:
            raise VolrenError("raycast: cut faces (clip caps) are not drawn on multi-channel volumes")
        channels = self.volume.channels  # type: ignore[union-attr]
        assert channels is not None  # `render` refuses a channel TF on a volume without its channels
        key = ("channels", tf.digest(), channels.digest, h,
               *(opts[k] for k in ("target_error", "classification_table", "termination_alpha", "brick_size",
                                   "empty_space_skipping")))  # fmt: skip
        h, chosen = self._chosen_step(key, lambda step, at: self._channel_args(tf, step, opts, at), "channels", h,
                                      opts, view, phase_mode)  # fmt: skip
        args = self._channel_args(tf, h, opts, view)
        return self._marched(args, args[1].distance, "channels", view, opts, progress, chosen)

    def _drawn_channels(self, tf: ChannelTransferFunction) -> tuple[list[int], NDArray[Any]]:
        """(the drawn channels: shown, weight above 0; their values as the march reads them: 8-bit
        where the volume's are, else float32, with the C march's slack), kept while they stay."""
        channels = self.volume.channels  # type: ignore[union-attr]
        assert channels is not None
        drawn = [c for c in range(tf.count) if tf.drawn_weight(c) > 0.0]
        key = (channels.digest, tuple(drawn))
        if self._channel_values is None or self._channel_values[0] != key:
            picked = channels.values[drawn] if drawn else channels.values[:1]
            kept = picked if picked.dtype == np.uint8 else picked.astype(np.float32)
            self._channel_values = (key, march_native.padded(kept))
        return drawn, self._channel_values[1]

    def _channel_args(
        self, tf: ChannelTransferFunction, h: float, opts: Mapping[str, Any], view: PixelView
    ) -> tuple:
        """The mixed march's arguments at step h (world units) for the view: the first drawn channel
        (the grid the march walks), the bricks where some drawn channel has opacity in its range,
        the channels' depth tables, the termination opacity."""
        volume = self.volume
        assert isinstance(volume, UniformVolume) and volume.channels is not None
        drawn, values = self._drawn_channels(tf)
        n = int(opts["classification_table"])
        post = np.zeros((len(values), n, 4))
        lo = np.zeros(len(values))
        scale = np.ones(len(values))
        for row, c in enumerate(drawn):
            class_tf = tf.tfs[c]
            vlo, vhi = volume.channels.value_ranges[c]
            tlo, thi = class_tf.value_range
            lo[row], hi = spanning(min(vlo, tlo), max(vhi, thi))
            scale[row] = (n - 1) / (hi - lo[row])
            rgb, a = class_tf.sample(np.linspace(lo[row], hi, n))
            post[row, :, :3] = rgb
            post[row, :, 3] = (
                tf.drawn_weight(c)
                * h
                / class_tf.opacity_unit_distance
                * -np.log1p(-np.minimum(a, MAX_OPACITY))
            )
        brick, skipping = int(opts["brick_size"]), bool(opts["empty_space_skipping"])
        pads = tuple(float(1.0 / s) for s in scale)
        empty = self._empty_bricks(("channels", tf.digest(), volume.channels.digest, brick, skipping, pads), brick, 0,
                                   skipping, lambda grid: _visible_channels(grid, values, drawn, tf, pads))  # fmt: skip
        table = ChannelClassification(values, post, float(h), lo, scale)
        term = float(opts["termination_alpha"]) if opts["termination_alpha"] < 1.0 else 2.0
        return values[0], EmptyBricks(empty, brick), view, table, term

    def _table_2d(self, tf: TransferFunction2D, nv: int) -> tuple[NDArray[np.float32], NDArray[np.int8], str]:
        """(table, its intervals' kinds, a digest of the table): the 2D TF sampled once per TF version at
        nv values and nv / 2 gradient magnitudes (the slicer's 512 x 256 by default), (r, g, b,
        extinction per world unit) with extinctions that cannot add `NEGLIGIBLE_OPACITY` to any ray
        dropped."""
        volume = self.volume
        assert isinstance(volume, UniformVolume)
        lo, hi = spanning(*tf.value_range)
        key = (id(tf), tf.version, lo, hi, nv)
        if self._table2d is None or self._table2d[0] != key:
            ng = max(2, nv // 2)
            values = np.linspace(lo, hi, nv)[None, :]
            magnitudes = np.linspace(0.0, float(tf.gradient_range[1]), ng)[:, None]
            rgb, alpha = tf.sample(values, magnitudes)  # extinction as `tf.extinction`, sampled once
            tau = -np.log1p(-np.minimum(alpha, MAX_OPACITY)) / tf.opacity_unit_distance
            b = volume.bounds
            tau[tau * math.hypot(b[1] - b[0], b[3] - b[2], b[5] - b[4]) < NEGLIGIBLE_OPACITY] = 0.0
            table = np.ascontiguousarray(np.concatenate([rgb, tau[..., None]], axis=-1), dtype=np.float32)
            digest = hashlib.blake2b(table.tobytes(), digest_size=16).hexdigest()
            self._table2d = (key, table, interval_kinds(table), digest)
        return self._table2d[1], self._table2d[2], self._table2d[3]

    def _march2d_args(
        self, tf: TransferFunction2D, h: float, opts: Mapping[str, Any], view: PixelView
    ) -> tuple:
        """`march2d`'s arguments at step h (world units) for the view: values, gradients, brick
        distances, table, termination opacity."""
        volume = self.volume
        assert isinstance(volume, UniformVolume) and self._values is not None
        if self._gradients is None:
            self._gradients = gradients(self._values, volume.spacing)
        table, kinds, digest = self._table_2d(tf, int(opts["table_2d"]))
        lo, hi = spanning(*tf.value_range)
        nv, ng = table.shape[1], table.shape[0]
        gmax = float(tf.gradient_range[1])
        tab = Table2D(table, float(lo), float((nv - 1) / (hi - lo)), float((ng - 1) / gmax), float(h), kinds)
        brick = int(opts["brick_size"])
        skipping = bool(opts["empty_space_skipping"])
        empty = self._empty_bricks(("2d", digest, lo, hi, brick, skipping), brick, 0, skipping,
                                   lambda grid: _visible_under_table(grid, table, lo, hi))  # fmt: skip
        term = float(opts["termination_alpha"]) if opts["termination_alpha"] < 1.0 else 2.0
        return self._values, self._gradients, EmptyBricks(empty, brick), view, tab, term

    @staticmethod
    def _every_pixel(args: tuple, width: int, height: int, progress: ProgressCallback | None,
                     march: MarchKind = "1d") -> tuple[NDArray[np.float32], NDArray[np.int64]]:  # fmt: skip
        """(image, the counts' totals): a ray through every pixel, in tiles."""
        image = np.empty((height, width, 4), np.float32)
        n_tiles = ((width + TILE - 1) // TILE) * ((height + TILE - 1) // TILE)
        counts = np.zeros((n_tiles, len(COUNTS)), np.int64)
        order = np.arange(n_tiles, dtype=np.int64)
        (kernel, _), numba_kernels = _kernels(march, args[0])
        with _chunks(numba_kernels, 1):  # tiles differ widely in cost: one at a time
            for start in range(0, n_tiles, TILES_PER_CALL):
                kernel(*args, order[start : start + TILES_PER_CALL], image.reshape(-1, 4), counts)
                if progress is not None:
                    progress(min(1.0, (start + TILES_PER_CALL) / n_tiles))
        return image, counts.sum(axis=0)

    @staticmethod
    def _refined(args: tuple, width: int, height: int, stride: int, tolerance: float,
                 progress: ProgressCallback | None,
                 march: MarchKind = "1d") -> tuple[NDArray[np.float32], NDArray[np.int64], int]:  # fmt: skip
        """(image, the counts' totals, rays cast): adaptive image refinement (`refine_image`), rays cast
        where a block's corner rays disagree, the rest interpolated."""
        from volren.kernels.image_refinement import refine_image

        totals = np.zeros(len(COUNTS), np.int64)

        def cast(pixels: NDArray[np.int64]) -> NDArray[np.float32]:
            rgba, counts = _march_listed(args, pixels, march)
            totals[:] += counts.sum(axis=0)
            return rgba

        rgba, rays = refine_image(cast, width, height, stride, float(tolerance), progress)
        image = rgba.astype(np.float32, copy=False).reshape(height, width, 4)
        return image, totals, rays

    def _project(self, tf: TransferFunction1D, mode: BlendMode, view: PixelView,
                 h: float) -> tuple[NDArray[np.float32], Mapping[str, float]]:  # fmt: skip
        """Maximum, minimum or average along each ray, coloured by the TF (DESIGN.md: colour and
        opacity of the projected value, no opacity where no finite value was met)."""
        from volren.renderers.raycast import march as K

        width, height = view.width, view.height
        acc = np.empty((width * height, 2))
        code = {BlendMode.MAXIMUM: K.MAXIMUM, BlendMode.MINIMUM: K.MINIMUM, BlendMode.AVERAGE: K.AVERAGE}[
            mode
        ]
        K.project(self._values, view, h, code, acc)
        hit = acc[:, 1] > 0
        value = np.where(hit, acc[:, 0], 0.0)
        if mode == BlendMode.AVERAGE:
            value = np.where(hit, value / np.where(hit, acc[:, 1], 1.0), 0.0)
        rgb, a = tf.sample(value)
        a = np.where(hit, a, 0.0)
        out = np.clip(np.concatenate([rgb * a[:, None], a[:, None]], axis=1), 0.0, 1.0)
        out[:, :3] = np.minimum(out[:, :3], out[:, 3:4])
        return out.reshape(height, width, 4).astype(np.float32), {"rays_hit": float(np.count_nonzero(hit))}
