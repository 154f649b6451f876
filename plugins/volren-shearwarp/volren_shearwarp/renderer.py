"""`shearwarp`: the shear-warp factorization (Lacroute and Levoy 1994) with pre-integration and
opacity and colour correction (Schulze, Kraus, Lang and Ertl 2003), on the CPU with numba.

Why: on a machine without a GPU (CI, servers, many laptops) this is the fastest way to draw a
uniform grid: slices are composited in object order into an intermediate image, each slice by a
scale and translation only, with empty space skipped by run-length encoding and opaque pixels by
skip links, and one 2D warp makes the final image. It is built only on volren's public contract
(volren.model, volren.renderers.base, volren.model.preintegration), the way a third party would.

How a frame goes (module per step):
1. `factorization`: the principal axis, the per-slice maps onto the intermediate image (shear and
   translation, or shear and scale under perspective), its size (`oversampling` intermediate
   pixels per output pixel, at least `pixels_per_voxel`, by default one per voxel; by default from
   the TF, `auto_oversampling`)
   and the warp matrix.
2. `classified`: the volume copy for that axis and its runs of possibly visible cells for the TF's
   opacity support (rebuilt only when the support changes).
3. `tables`: pre-integration tables (or post-classification LUTs) for this view's segment lengths.
4. `composite`: slabs front to back, in blocks of slices, progress after each block.
5. `warp`: every output pixel's ray resampled from the intermediate image (Catmull-Rom).

Sampling: the rays cross every slice along the principal axis (shear-warp's own rate: a bilinear
sample in a slice is an exact trilinear sample, and pre-integration integrates the segment between
two of them exactly for data linear along it). `step` below 0.5 adds planes between slices:
ceil(slice spacing / (2 step smallest spacing)) segments per slab (1 at the default 0.5, 2 at 0.25),
sampled trilinearly. `step` 1 and above composites every stride-th slice only, stride =
floor(2 step smallest spacing / slice spacing) (`slice_stride`: 2 at step 1, 4 at step 2), one segment
from slice to slice with tables for its length: a draft at 1/stride of the segments, like a ray
caster's longer step (the last slab is shorter where the stride does not divide the slices, and is
corrected to its length). Blend modes maximum / minimum / average, jitter and a near or far plane
that cuts the volume take every slice.

Clipping: only what lies between the camera's near and far planes is drawn. Along each intermediate
ray the depth is linear in the slice index, so each ray keeps an interval of slices
(`Factorization.clip_limits`); only when a plane cuts the volume's box (never for cameras from
`Camera.orbit` or `reset_clipping_range`) does compositing take those intervals: segments wholly
between the planes stay on the fast path, the few that a plane cuts go the general way (sampled at
the cut and corrected to their part), those outside are skipped; the default frame runs as before.
A clip region (`RenderSettings.clip`: oblique planes and a crop box) narrows the same intervals
(`Factorization.region_limits`: a plane's value is linear in u along a ray), so its cut is flat, each
cut segment sampled at the cut and corrected to its kept part; unlike the near and far planes it
keeps the slice stride (a slab of several slices maps u through its own), so neither the step, the
tables nor the runs depend on where the planes are.

Jitter (the `jitter` setting): each intermediate pixel's samples move off the slices by a seeded
offset in [0, 1) of the plane spacing (`jitter_seed`), so that slice-aligned sampling artifacts turn
into noise; its segments run from sample to sample across slices (`composite._jittered_pixel`),
which takes the general way, and its first and last segments from where the ray enters and to where
it leaves. Maximum, minimum and average are exact along the piecewise-linear ray and take no jitter.

Counters: samples (segments composited), rays (intermediate pixels), empty_pixels_skipped (pixel
slabs skipped by the runs), pixels_terminated, slices (composited), slice_stride, planes_per_slab, intermediate_width /
_height, table_lengths, clipped (1 when the near or far plane or a clip region cut the volume).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from typing import Any, ClassVar

import numba
import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError
from volren.kernels.shading import ShadeParams, gradient_threshold
from volren.model import BlendMode, Camera, TransferFunction1D, UniformVolume
from volren.model.channels import ChannelTransferFunction
from volren.model.downsample import FACTORS as DOWNSAMPLE_FACTORS
from volren.model.downsample import downsample
from volren.model.labels import LabelTransferFunction
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
from volren_shearwarp.bundles import (
    Classification,
    Clipping,
    Intermediate,
    Jitter,
    Runs,
    SlabGeometry,
    Termination,
    ViewVectors,
)
from volren_shearwarp.classified import ClassifiedVolume, OpacitySupport, slab_pairs
from volren_shearwarp.composite import AVERAGE, MAXIMUM, MINIMUM, composite_slabs, project_slabs
from volren_shearwarp.factorization import Factorization, factorize, index_frame
from volren_shearwarp.mixed_composite import composite_classes
from volren_shearwarp.mixed_frame import MixedScenes
from volren_shearwarp.tables import (
    GRID_MARGIN,
    LENGTH_RATIO,
    TablePool,
    grid_ids,
    grid_length,
    pixel_slots,
    slot_bounds,
)
from volren_shearwarp.warp import warp

#: Intermediate rows a thread composites together, slab by slab (the kernels' `row_block`). Why: neighbouring
#: rows meet neighbouring scanlines of each slice, so a block reads a slice's data once, in order, where row
#: after row (all slabs of one row, then the next) fetched each slice scanline again for every row once the
#: row's other slices had pushed it out of the cache. docs/shearwarp.md: turning frames 1.09-1.20x
#: faster on aneurism smooth, bonsai smooth and opaque and engine opaque, the others unchanged, the same
#: images to the bit; 16 rows measured the same, 1 (row after row) and 96 slower.
ROW_BLOCK = 8
#: Row blocks per dynamically scheduled chunk of the parallel kernels.
ROW_CHUNK = 1
#: Compositing time (ms, the previous frame's) per block of slices, one progress call after each block. Why not
#: a fixed count: each block is a parallel launch ending at a barrier, which on a shared machine waits for a
#: preempted thread (16 blocks cost bonsai 30% more than 4 under load), so a fast frame runs as one launch and
#: a slow one (large volume, fine settings) still reports progress, and can be cancelled, every ~BLOCK_MS.
BLOCK_MS = 60.0
#: Blocks per frame at most, and for the first frame (no measurement yet).
MAX_BLOCKS, FIRST_BLOCKS = 16, 4
#: Most planes per slab that `step` may ask for.
MAX_PLANES_PER_SLAB = 256
#: Most slices a slab may span (`slice_stride`).
MAX_SLICE_STRIDE = 8
#: Runs are built for rays moving up to this many cells per slice (steeper views go without).
MAX_RUN_SHEAR = 3
#: Under perspective, tables are made for segment lengths up to this many times the axial slab length at once
#: (rays 60 degrees off the principal axis; bonsai turning about its axes needs up to 2.05).
TURNING_SPAN = 2.0
#: A pool holding more lengths than this is started afresh.
MAX_POOL_LENGTHS = 512

OPTIONS: tuple[OptionSpec, ...] = (
    OptionSpec(
        "oversampling",
        "auto",
        "float",
        "intermediate-image pixels per output pixel along each axis (at least `pixels_per_voxel` per voxel "
        "is kept), or 'auto': from the TF's sharpness (`auto_oversampling`), 0.5 for a translucent TF up to "
        "2 for one that makes a voxel opaque",
        low=0.25,
        high=8.0,
        words=("auto",),
    ),
    OptionSpec(
        "pixels_per_voxel",
        1.0,
        "float",
        "the fewest intermediate-image pixels per voxel along each axis: 1 resolves every voxel; below 1 a "
        "draft that samples each slice more coarsely than its voxels (as VTK's image sample distance casts "
        "fewer rays than pixels), at about its square of the compositing: on translucent TFs where a voxel "
        "covers more than one output pixel",
        low=0.25,
        high=1.0,
    ),
    OptionSpec(
        "table_size",
        "auto",
        "int",
        "entries per axis of the pre-integration table / classification LUT, or 'auto': 128 for a "
        "translucent TF, 256 otherwise (`auto_table_size`)",
        low=16,
        high=4096,
        words=("auto",),
    ),
    OptionSpec(
        "lookup",
        "nearest",
        "choice",
        "table lookup (the seed's two variants; nearest: 3x cheaper, RMSE within 0.0005 of bilinear on the "
        "shared scenes at 256 entries)",
        choices=("nearest", "bilinear"),
    ),
    OptionSpec(
        "warp_filter",
        "cubic",
        "choice",
        "the warp's resampling of the intermediate image: 'cubic' (Catmull-Rom) or 'bilinear'",
        choices=("cubic", "bilinear"),
    ),
    OptionSpec("empty_space_skipping", True, "bool", "skip the runs of cells the TF makes transparent"),
    OptionSpec("early_termination", True, "bool", "stop compositing pixels once opaque"),
    OptionSpec(
        "termination_alpha", 0.995, "float", "opacity at which a pixel counts as opaque", low=0.5, high=1.0
    ),
    OptionSpec(
        "opacity_correction",
        True,
        "bool",
        "correct each segment's opacity (and colour) to its length, 1 - (1 - a)^(d / d_u) (false draws every "
        "slab as if d_u long: the seed's 'NC' column, for measuring what the correction costs, not for use)",
    ),
    OptionSpec(
        "length_ratio",
        LENGTH_RATIO,
        "float",
        "under perspective, the ratio between neighbouring segment lengths that get their own table: a "
        "segment's opacity is off by at most (ratio - 1) / 2 of its optical depth; coarser makes fewer "
        "tables per TF",
        low=1.001,
        high=1.25,
    ),
    OptionSpec(
        "jitter_seed", 0, "int", "seed of the per-pixel sample offsets drawn with the `jitter` setting", low=0
    ),
    OptionSpec(
        "downsample",
        1,
        "choice",
        "render a copy of the volume reduced this many times along each axis (`volren.model.downsample`): a "
        "draft at about 1/factor^3 of the compositing",
        choices=tuple(DOWNSAMPLE_FACTORS),
    ),
)

_MODES = {BlendMode.MAXIMUM: MAXIMUM, BlendMode.MINIMUM: MINIMUM, BlendMode.AVERAGE: AVERAGE}


def voxel_optical_depth(tf: TransferFunction1D, mean_spacing: float) -> float:
    """The largest optical depth tau of one voxel spacing the TF gives (its sharpness, for the 'auto' options)."""
    alpha = float(np.max(tf.opacity_points[:, 1])) if len(tf.opacity_points) else 0.0
    return -math.log1p(-min(max(alpha, 0.0), 1.0 - 1e-6)) * mean_spacing / tf.opacity_unit_distance


def auto_oversampling(tau: float) -> float:
    """2 tau, clamped to [0.5, 2] (the factorization keeps at least one intermediate pixel per
    voxel whatever this is). Why: the warp's resampling blurs the intermediate image by about one
    of its pixels, which costs accuracy only where the image has sharp edges, and those come from
    TFs that make a voxel or two opaque (silhouettes of surfaces); a translucent TF's image is as
    smooth as the data, which one intermediate pixel per voxel resolves even where a voxel covers
    more than one output pixel. Measured on the shared scenes (docs/shearwarp.md): bonsai smooth
    (tau 0.36) RMSE 0.0025 at 1 and 0.0032 at one pixel per voxel, with 1.7x fewer segments;
    aneurism's thin vessels (tau 0.92) need about 1.5; opaque TFs 2. Compositing costs the square."""
    return min(max(2.0 * tau, 0.5), 2.0)


def run_extent(stride: int, max_shear: float) -> int:
    """Cells a ray may move in the slice plane across one slab of `stride` slices, at least 1: the
    size of the runs' blocks (`classified`). Why the margin: at a shear of exactly 1 (a view at 45
    degrees) rounding may put a back point a hair into the next cell, whose vertex the block must
    hold. Why no larger minimum: a camera turning through a shear of 1 pays one ranges pass for the
    new extent (about 200 ms on bonsai, once per axis and extent), and extent 1 composites 9-18 %
    faster than 2 where it applies (docs/shearwarp.md)."""
    return max(1, math.ceil(stride * max_shear + 1e-6))


def auto_table_size(tau: float) -> int:
    """128 entries where 2 tau < 1 (the TFs `auto_oversampling` draws at under one intermediate pixel
    per output pixel), else 256. Why: a segment's table entry is off by the TF's change over half an
    entry's value step, which matters in proportion to the segment's opacity, small for a translucent
    TF; a table of 128 entries is 4x smaller and cheaper to build. Measured (docs/shearwarp.md):
    bonsai smooth RMSE 0.00323 -> 0.00325, 15% less frame time, a colour edit 215 -> 94 ms; on spiky
    and opaque TFs 128 entries cost up to 0.0011 (bonsai spiky), so they keep 256."""
    return 128 if 2.0 * tau < 1.0 else 256


def slice_stride(step: float, slice_spacing: float, unit: float, slices: int) -> int:
    """Slices per slab for `step` (in units of the smallest spacing, `unit`; 0.5 is one slice per
    slab on an isotropic grid, shear-warp's own rate, see `planes` in `_render`): floor(2 step unit /
    slice spacing), 1 to MAX_SLICE_STRIDE, and at most slices - 1."""
    stride = int(math.floor(2.0 * step * unit / slice_spacing + 1e-9))
    return max(1, min(stride, MAX_SLICE_STRIDE, slices - 1))


def _with_region(fac: Factorization, limits: tuple[NDArray, NDArray] | None,
                 half_spaces: NDArray[np.float64]) -> tuple[NDArray, NDArray] | None:  # fmt: skip
    """The near and far planes' intervals of u per intermediate ray (`Factorization.clip_limits`, None:
    every ray whole) narrowed to the clip region's half-spaces (`Factorization.region_limits`); None
    when neither clips."""
    if len(half_spaces) == 0:
        return limits
    lo, hi = fac.region_limits(half_spaces)
    if limits is not None:
        lo, hi = np.maximum(lo, limits[0]), np.minimum(hi, limits[1])
    return np.ascontiguousarray(lo), np.ascontiguousarray(hi)


def strided_order(order: NDArray[np.int64], stride: int) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """Every stride-th slice of the compositing order, the last slice kept, and each slab's length
    in whole slabs (index m: the slab between entries m - 1 and m; below 1 only for a short last one)."""
    picked = order[::stride]
    if picked[-1] != order[-1]:
        picked = np.append(picked, order[-1])
    frac = np.ones(len(picked))
    frac[1:] = np.abs(np.diff(picked)) / stride
    return np.ascontiguousarray(picked, dtype=np.int64), frac


def _level(
    preintegrated: bool, step: float, oversampling: float, pixels_per_voxel: float | None = None
) -> QualityLevel:
    """A quality level at a fixed `oversampling`, for drafts also `pixels_per_voxel` (below one: intermediate
    pixels wider than voxels, `factorize`'s min_scale), labelled as the benchmarks and this
    package's own `quality_levels.json` name it."""
    label = f"{'pre-integrated' if preintegrated else 'post-classified'}, oversampling {oversampling:g}"
    options: dict[str, float] = {"oversampling": oversampling}
    if pixels_per_voxel is not None:
        label += f", {pixels_per_voxel:g} pixels per voxel"
        options["pixels_per_voxel"] = pixels_per_voxel
    if step != 0.5:
        label += f", step {step:g}"
    return QualityLevel(label, step=step, preintegration=preintegrated, options=options)


def _rows(height: int) -> NDArray[np.int64]:
    """The intermediate rows, for kernels that hand them to threads ROW_BLOCK rows at a time (dynamic
    chunks: a static split waits for the slowest thread, and on a shared machine one core is often
    busy elsewhere)."""
    return np.arange(height, dtype=np.int64)


class ShearWarpRenderer(RendererBase):
    """Pre-integrated shear-warp on uniform grids: composite, maximum, minimum, average, shading."""

    name: ClassVar[str] = "shearwarp"
    capabilities: ClassVar[Capabilities] = Capabilities(
        kinds={
            "uniform": KindSupport(
                tf_dims=frozenset({1}),
                preintegration=True,
                shading=True,
                blend_modes=frozenset(BlendMode),
                # measured with the full kit (docs/conformance/shearwarp.txt): RMSE up to 0.0058 (the
                # NaN scene), 0.0049 (the ramp seen along +x), the point 0.058 px off
                accuracy=Accuracy(rmse=0.01, position_px=0.1),
                # from inside, the slices lie on both sides of the eye along every axis (`choose_axis`)
                eye_inside=False,
                clip_region=True,
                # composite and post-classified, each sample classified on the slices (`mixed_composite`): a
                # label's or several channels' classification is not a function of one scalar, so it has no
                # 1D LUT or pre-integration table per segment length
                labels=True,
                labels_preintegration=False,
                channels=True,
            )
        },
        backend="cpu",
        summary="shear-warp (numba): RLE empty-space skipping, early termination, pre-integration, 2D warp",
        quality=(
            # intermediate pixels up to twice a voxel's width (`pixels_per_voxel`): 2-4x fewer segments at VTK's step-2
            # error or below on 11 of the 12 shared scenes, where a voxel covers more than an output pixel
            # (docs/shearwarp.md; bonsai's smooth and opaque TFs need 0.7 per voxel, aneurism's smooth one 1)
            _level(False, step=1.0, oversampling=0.25, pixels_per_voxel=0.5),
            _level(True, step=2.0, oversampling=0.25, pixels_per_voxel=0.5),
            _level(True, step=1.0, oversampling=0.25, pixels_per_voxel=0.5),
            _level(False, step=0.5, oversampling=0.25, pixels_per_voxel=0.5),
            _level(True, step=0.5, oversampling=0.25, pixels_per_voxel=0.5),
            _level(False, step=1.0, oversampling=0.25, pixels_per_voxel=0.7),
            _level(True, step=1.0, oversampling=0.25, pixels_per_voxel=0.7),
            # every 2nd / 4th slice (`slice_stride`): fewer segments, where the data is smooth along the
            # principal axis as accurate as VTK's step 2 (docs/shearwarp.md: bonsai smooth 0.0044 at step
            # 1 post-classified against VTK's 0.0069, at 0.6x every slice's time; spiky and opaque TFs at step 2
            # pre-integrated)
            _level(False, step=1.0, oversampling=0.5),
            _level(True, step=2.0, oversampling=0.5),
            _level(True, step=1.0, oversampling=0.5),
            # half an intermediate pixel per output pixel (one per voxel is kept): the classic shear-warp
            # image where voxels cover several pixels, the warp's Catmull-Rom filter doing the rest
            _level(False, step=0.5, oversampling=0.5),
            _level(True, step=0.5, oversampling=0.5),
            _level(False, step=0.5, oversampling=1.0),
            _level(True, step=0.5, oversampling=1.0),
            QualityLevel("pre-integrated, oversampling auto (default)", step=0.5, preintegration=True),
            QualityLevel("pre-integrated, oversampling 2, bilinear lookup", step=0.5, preintegration=True,
                         options={"oversampling": 2.0, "lookup": "bilinear"}),
            QualityLevel("pre-integrated, oversampling 3, step 0.25, bilinear lookup", step=0.25, preintegration=True,
                         options={"oversampling": 3.0, "lookup": "bilinear"}),
        ),
        # a TF drag rebuilds the pre-integration tables each edit: 81 -> 49 ms a 400x300 bonsai preview at 64
        # entries; its 19 lengths' tables took 13-17 ms of those, 5 lengths at ratio 1.1 took 3-4 ms (cProfile)
        tf_drag_options={"table_size": 64, "length_ratio": 1.1},
    )  # fmt: skip
    options: ClassVar[tuple[OptionSpec, ...]] = OPTIONS

    def __init__(self) -> None:
        super().__init__()
        self._classified: ClassifiedVolume | None = None
        self._coarse: dict[
            int, tuple[UniformVolume, ClassifiedVolume]
        ] = {}  # by downsampling factor, made on demand
        self._support: tuple[tuple, OpacitySupport] | None = None
        self._pools: dict[str, TablePool] = {}
        self._buffers: dict[str, NDArray] = {}
        self._slab_ms: float | None = None  # the last frame's slab loop (ms), which sets the block count
        self._mixed: MixedScenes | None = None  # label and channel layouts (`mixed_frame`)

    # ------------------------------------------------------------------------- state
    def _volume_changed(self) -> None:
        volume = self.volume
        assert isinstance(volume, UniformVolume)
        self._classified = ClassifiedVolume(volume)
        self._mixed = MixedScenes(volume)
        self._coarse.clear()
        self._support = None
        self._pools.clear()

    def _level(self, factor: int) -> tuple[UniformVolume, ClassifiedVolume]:
        """The volume reduced `factor` times and its classified copy (the volume itself for 1)."""
        volume = self.volume
        assert isinstance(volume, UniformVolume) and self._classified is not None
        if factor == 1:
            return volume, self._classified
        if factor not in self._coarse:
            coarse = downsample(volume, factor)
            self._coarse[factor] = (coarse, ClassifiedVolume(coarse))
        return self._coarse[factor]

    def release(self) -> None:
        self._classified = None
        self._mixed = None
        self._coarse.clear()
        self._support = None
        self._pools.clear()
        self._buffers.clear()
        super().release()

    def _scratch(self, name: str, shape: tuple[int, ...], dtype: type) -> NDArray:
        """A buffer of `shape` reused from frame to frame (the kernels clear what they use): fresh
        zeroed arrays cost page faults on every frame."""
        size = math.prod(shape)
        flat = self._buffers.get(name)
        if flat is None or flat.size < size or flat.dtype != dtype:
            flat = self._buffers[name] = np.empty(max(size, 1), dtype)
        return flat[:size].reshape(shape)

    @property
    def classified(self) -> ClassifiedVolume | None:
        """The axis copies and runs (for measurements and tests)."""
        return self._classified

    def _opacity_support(self, tf: TransferFunction1D, lo: float, hi: float) -> OpacitySupport:
        key = (id(tf), tf.version, lo, hi)
        if self._support is None or self._support[0] != key:
            self._support = (key, OpacitySupport.of(tf, lo, hi))
        return self._support[1]

    def _pool(self, kind: str, tf: TransferFunction1D, n: int, lo: float, hi: float) -> TablePool:
        key = (id(tf), tf.version, n, lo, hi)
        pool = self._pools.get(kind)
        if pool is None or pool.key != key or len(pool.slots) > MAX_POOL_LENGTHS:
            pool = TablePool(key, kind)
            self._pools[kind] = pool
        return pool

    # ------------------------------------------------------------------------ render
    def _render(
        self, camera: Camera, width: int, height: int, progress: ProgressCallback | None
    ) -> tuple[NDArray[np.float32], Mapping[str, float]]:
        tf = self.transfer_function
        if isinstance(tf, LabelTransferFunction | ChannelTransferFunction):
            return self._render_mixed(tf, camera, width, height, progress)
        assert isinstance(tf, TransferFunction1D)
        settings = self.settings
        opts = self.opts
        full = self.volume
        assert isinstance(full, UniformVolume)
        volume, classified = self._level(int(opts["downsample"]))
        oversampling = opts["oversampling"]
        tau = voxel_optical_depth(tf, volume.mean_spacing)
        if oversampling == "auto":
            oversampling = auto_oversampling(tau)
        fac = factorize(camera, volume, width, height, oversampling, min_scale=opts["pixels_per_voxel"])
        copy = classified.copy(fac.axis)
        has_nan = classified.has_nan
        values = copy.values
        spacing_c = float(fac.spacing[2])
        step_length = settings.step * volume.characteristic_length
        planes = int(min(MAX_PLANES_PER_SLAB, max(1, math.ceil(spacing_c / (2.0 * step_length) - 1e-9))))
        vlo, vhi = full.value_range  # tables and the opacity support span the data's range at every level
        tlo, thi = tf.value_range
        lo, hi = min(vlo, tlo), max(vhi, thi)
        lo, hi = spanning(lo, hi)
        n = auto_table_size(tau) if opts["table_size"] == "auto" else int(opts["table_size"])
        order = fac.order
        rows = _rows(fac.height)
        limits = fac.clip_limits(camera, volume)  # None unless the near or far plane cuts the volume
        near_far = limits is not None
        limits = _with_region(fac, limits, settings.clip.half_spaces_in_grid(*index_frame(volume)[:2]))
        clipping = limits is not None
        clip_lo, clip_hi = limits if limits is not None else (np.zeros((1, 1)), np.zeros((1, 1)))
        counters: dict[str, float] = {
            "rays": float(fac.width * fac.height), "slices": float(len(order)), "planes_per_slab": float(planes),
            "intermediate_width": float(fac.width), "intermediate_height": float(fac.height),
            "clipped": float(clipping), "slice_stride": 1.0,
        }  # fmt: skip

        if settings.blend_mode is not BlendMode.COMPOSITE:
            acc = np.zeros((fac.height, fac.width, 2))
            lengths = fac.pixel_lengths() / planes
            geom = SlabGeometry(values, has_nan, order, np.ones(len(order)), planes, fac.alpha_a, fac.beta_a,
                                fac.alpha_b, fac.beta_b, rows, ROW_BLOCK, 1.0 / fac.spacing)  # fmt: skip
            clip = Clipping(clipping, clip_lo, clip_hi)
            self._blocks(
                progress,
                len(order),
                lambda m0, m1: project_slabs(geom, m0, m1, acc, _MODES[settings.blend_mode], lengths, clip),
            )
            hit = acc[..., 1] > 0
            value = np.where(hit, acc[..., 0], 0.0)
            if settings.blend_mode is BlendMode.AVERAGE:
                value = np.where(hit, value / np.where(hit, acc[..., 1], 1.0), 0.0)
            rgb, a = tf.sample(value)
            a = np.where(hit, a, 0.0)
            inter = np.concatenate([rgb * a[..., None], a[..., None]], axis=-1).astype(np.float32)
            image = self._warp(inter, fac, width, height, opts)
            counters["samples"] = float(np.count_nonzero(hit))
            return image, counters

        support = self._opacity_support(tf, vlo, vhi)
        if support.empty:
            if progress is not None:
                progress(1.0)
            counters.update(samples=0.0, empty_pixels_skipped=0.0, pixels_terminated=0.0, table_lengths=0.0)
            return np.zeros((height, width, 4), np.float32), counters
        stride = (
            1
            if near_far or settings.jitter
            else slice_stride(settings.step, spacing_c, volume.characteristic_length, len(order))
        )
        order, slab_frac = strided_order(order, stride)
        counters.update(slices=float(len(order)), slice_stride=float(stride))
        pairs, run_slab = slab_pairs(order)  # the runs number slabs by their lower slice
        extent = run_extent(stride, fac.max_shear)
        use_runs = bool(opts["empty_space_skipping"]) and fac.max_shear <= MAX_RUN_SHEAR
        if use_runs:
            runs = classified.runs(fac.axis, support, extent, pairs)
            offsets, starts, ends = runs.offsets, runs.starts, runs.ends
        else:
            offsets, starts, ends = np.zeros(1, np.int64), np.zeros(0, np.int32), np.zeros(0, np.int32)
        per_slab = stride / planes  # slices a segment spans

        # tables by segment length: exact for a parallel view, snapped to a grid under perspective
        shading = bool(settings.shade)
        kind = ("lit" if shading else "pre") if settings.preintegration else "post"
        pool = self._pool(kind, tf, n, lo, hi)
        per_pixel = fac.perspective and bool(opts["opacity_correction"])  # a table per pixel's segment length
        layers = self._scratch("layers", (fac.height, fac.width) if per_pixel else (1, 1), np.int32)
        if not opts["opacity_correction"]:
            grid = [tf.opacity_unit_distance]
            layers[0, 0] = pool.gather(tf, n, lo, hi, grid)[0]
        elif per_pixel:
            col_d2, row_d2, dc2, inv_norm = fac.length_terms()
            inv_norm *= per_slab
            shortest = math.sqrt(col_d2.min() + row_d2.min() + dc2) * inv_norm
            longest = math.sqrt(col_d2.max() + row_d2.max() + dc2) * inv_norm
            reference = volume.mean_spacing
            ratio = opts["length_ratio"]
            id_lo, id_hi = grid_ids(shortest, longest, reference, ratio)
            grid = [grid_length(i, reference, ratio) for i in range(id_lo, id_hi + 1)]
            # the batch that makes missing tables also makes every length from the axial one to TURNING_SPAN x it:
            # a camera turning about the volume then rarely waits for tables (without, bonsai turning 2 degrees a
            # frame needed a batch every 2-3 frames, about 9 ms a frame)
            ax_lo, ax_hi = grid_ids(
                spacing_c * per_slab, TURNING_SPAN * spacing_c * per_slab, reference, ratio
            )
            # ... but not at a TF's first frame: a TF drag makes a new TF every frame, and with the batch each of
            # bonsai's drag previews made twice the lengths it needed (tables 30 ms of 80 a preview; 15 ms without)
            extra = [grid_length(i, reference, ratio)
                     for i in range(min(id_lo, ax_lo) - GRID_MARGIN, max(id_hi, ax_hi) + GRID_MARGIN + 1)
                     ] if pool.slots else None  # fmt: skip
            slots = pool.gather(tf, n, lo, hi, grid, extra)
            pixel_slots(
                col_d2, row_d2, dc2, slot_bounds(id_lo, id_hi, reference, inv_norm, ratio), slots, layers
            )
        else:
            grid = [fac.slab_length * per_slab]
            layers[0, 0] = pool.gather(tf, n, lo, hi, grid)[0]
        counters["table_lengths"] = float(len(grid))
        front = pool.front
        back = pool.back if pool.back is not None else np.zeros((1, 1, 1, 4), np.float32)
        assert front is not None
        if kind == "post":
            table, lut = np.zeros((1, 1, 1, 4), np.float32), front
        else:
            table, lut = front, np.zeros((1, 1, 4), np.float32)

        light = -np.asarray(camera.direction, np.float64)[list(fac.perm)]
        half = light.copy()  # parallel: the view vector is the light's
        ray_dirs = np.zeros((1, 1, 3))
        if shading and fac.perspective:  # the view vector differs per ray: H per intermediate pixel
            a0, b0 = fac.origin_ab
            h = 1.0 / fac.scale
            da = (a0 + h * np.arange(fac.width) - fac.eye[0]) * fac.spacing[0]
            db = (b0 + h * np.arange(fac.height) - fac.eye[1]) * fac.spacing[1]
            dc = (fac.plane - fac.eye[2]) * fac.spacing[2]
            ray_dirs = np.empty((fac.height, fac.width, 3))
            ray_dirs[..., 0] = da[None, :]
            ray_dirs[..., 1] = db[:, None]
            ray_dirs[..., 2] = dc
            ray_dirs /= np.linalg.norm(ray_dirs, axis=-1, keepdims=True)
        span = vhi - vlo
        gthr = gradient_threshold(span, volume.characteristic_length)

        shape = (fac.height, fac.width)
        rgba = self._scratch("rgba", shape + (4,), np.float32)
        buf_x = self._scratch("buf_x", shape, np.float32)
        buf_d = self._scratch("buf_d", shape if shading else (1, 1), np.float32)
        buf_s = self._scratch("buf_s", shape if shading else (1, 1), np.float32)
        stamp = self._scratch("stamp", shape, np.int32)
        skip = self._scratch("skip", shape, np.int32)
        per_row = self._scratch("per_row", (fac.height, 4), np.int64)
        scale = (n - 1) / (hi - lo)
        inv_sp = 1.0 / fac.spacing

        jitter = bool(settings.jitter)
        if jitter:  # a fixed offset per intermediate pixel, from the seed: the same view draws the same image
            offsets_u = np.random.default_rng(int(opts["jitter_seed"])).random(shape, dtype=np.float32)
        else:
            offsets_u = np.zeros((1, 1), np.float32)
        buf_len = self._scratch("buf_len", shape if jitter else (1, 1), np.float32)

        geom = SlabGeometry(values, has_nan, order, slab_frac, planes, fac.alpha_a, fac.beta_a, fac.alpha_b,
                            fac.beta_b, rows, ROW_BLOCK, inv_sp)  # fmt: skip
        intermediate = Intermediate(rgba, buf_x, buf_d, buf_s, buf_len, stamp, skip, per_row)
        tables = Classification(layers, per_pixel, table, back, lut, bool(settings.preintegration),
                                opts["lookup"] == "bilinear", float(lo), float(scale))  # fmt: skip
        run_set = Runs(use_runs, offsets, starts, ends, extent, run_slab)
        termination = Termination(bool(opts["early_termination"]), float(opts["termination_alpha"]))
        shade = ShadeParams(shading, float(settings.ambient), float(settings.diffuse), float(settings.specular),
                            float(settings.specular_power), float(gthr), float(light[0]), float(light[1]),
                            float(light[2]))  # fmt: skip
        view = ViewVectors(half, ray_dirs)
        clip = Clipping(clipping, clip_lo, clip_hi)
        jittered = Jitter(jitter, offsets_u)

        def block(m0: int, m1: int) -> None:
            composite_slabs(
                geom, m0, m1, intermediate, tables, run_set, termination, shade, view, clip, jittered
            )

        self._blocks(progress, len(order), block)
        image = self._warp(rgba, fac, width, height, opts)
        totals = per_row.sum(axis=0)
        counters.update(samples=float(totals[0]), empty_pixels_skipped=float(totals[1]),
                        pixels_terminated=float(totals[2]), runs=1.0 if use_runs else 0.0)  # fmt: skip
        return image, counters

    def _render_mixed(
        self,
        tf: LabelTransferFunction | ChannelTransferFunction,
        camera: Camera,
        width: int,
        height: int,
        progress: ProgressCallback | None,
    ) -> tuple[NDArray[np.float32], Mapping[str, float]]:
        """A frame of a label or multi-channel volume (`mixed_composite`): composite, post-classified, each
        sample classified on the slices; the plain frame's factorization, stride, clipping and runs."""
        settings, opts = self.settings, self.opts
        labels = isinstance(tf, LabelTransferFunction)
        what = "label volumes" if labels else "multi-channel volumes"
        if settings.blend_mode is not BlendMode.COMPOSITE:
            raise VolrenError(f"renderer {self.name} draws {what} composite only, not {settings.blend_mode}")
        for flag, why in ((settings.shade, "shading"), (settings.jitter, "jitter"),
                          (int(opts["downsample"]) != 1, "the option downsample")):  # fmt: skip
            if flag:
                raise VolrenError(f"renderer {self.name} draws {what} without {why}")
        volume = self.volume
        assert isinstance(volume, UniformVolume) and self._classified is not None and self._mixed is not None
        classified, mixed = self._classified, self._mixed
        counters: dict[str, float] = {"samples": 0.0, "empty_pixels_skipped": 0.0, "pixels_terminated": 0.0}
        if isinstance(tf, LabelTransferFunction):
            assert volume.labels is not None
            classes = tf.classes(volume.labels.max_label)
            taus = [voxel_optical_depth(class_tf, volume.mean_spacing) for class_tf in classes.tfs]
        else:
            drawn = [c for c in range(tf.count) if tf.drawn_weight(c) > 0.0]
            taus = [tf.drawn_weight(c) * voxel_optical_depth(tf.tfs[c], volume.mean_spacing) for c in drawn]
        if not taus:  # every label or channel hidden
            return np.zeros((height, width, 4), np.float32), counters
        tau = max(taus)
        oversampling = auto_oversampling(tau) if opts["oversampling"] == "auto" else opts["oversampling"]
        fac = factorize(camera, volume, width, height, oversampling, min_scale=opts["pixels_per_voxel"])
        values = classified.copy(fac.axis).values
        spacing_c = float(fac.spacing[2])
        step_length = settings.step * volume.characteristic_length
        planes = int(min(MAX_PLANES_PER_SLAB, max(1, math.ceil(spacing_c / (2.0 * step_length) - 1e-9))))
        n = auto_table_size(tau) if opts["table_size"] == "auto" else int(opts["table_size"])
        limits = fac.clip_limits(camera, volume)
        near_far = limits is not None
        grid_origin, grid_spacing = index_frame(volume)[:2]
        limits = _with_region(
            fac, limits, settings.clip.half_spaces_in_grid(grid_origin.tolist(), grid_spacing.tolist())
        )
        clip_lo, clip_hi = limits if limits is not None else (np.zeros((1, 1)), np.zeros((1, 1)))
        order = fac.order
        stride = (
            1
            if near_far
            else slice_stride(settings.step, spacing_c, volume.characteristic_length, len(order))
        )
        order, slab_frac = strided_order(order, stride)
        pairs, run_slab = slab_pairs(order)
        extent = run_extent(stride, fac.max_shear)
        use_runs = bool(opts["empty_space_skipping"]) and fac.max_shear <= MAX_RUN_SHEAR
        per_slab = stride / planes
        halves = fac.pixel_lengths() * per_slab * 0.5  # half of each ray's segment (world units)
        # the tables' segment: every ray's under a parallel view, else the axial one (`label_sample` corrects)
        h = float(halves[0, 0]) if not fac.perspective else 0.5 * per_slab * spacing_c
        if isinstance(tf, LabelTransferFunction):
            classification: Any = mixed.label_classification(fac.axis, tf, classes, n, h, volume.value_range)
            runs, visible = mixed.label_runs(fac.axis, values, classes, classification.cells, volume.value_range,
                                             extent, pairs, use_runs, 1.0 / classification.scale)  # fmt: skip
        else:
            classification, runs, visible = mixed.channel_frame(
                fac.axis, tf, drawn, n, h, extent, pairs, use_runs
            )
        counters.update(rays=float(fac.width * fac.height), slices=float(len(order)), planes_per_slab=float(planes),
                        intermediate_width=float(fac.width), intermediate_height=float(fac.height),
                        clipped=float(limits is not None), slice_stride=float(stride),
                        runs=float(runs is not None))  # fmt: skip
        if not visible:
            if progress is not None:
                progress(1.0)
            return np.zeros((height, width, 4), np.float32), counters
        if runs is None:
            run_set = Runs(
                False, np.zeros(1, np.int64), np.zeros(0, np.int32), np.zeros(0, np.int32), extent, run_slab
            )
        else:
            run_set = Runs(True, runs.offsets, runs.starts, runs.ends, extent, run_slab)
        shape = (fac.height, fac.width)
        rgba = self._scratch("rgba", shape + (4,), np.float32)
        front = self._scratch("front", shape + (4,), np.float32)
        stamp = self._scratch("stamp", shape, np.int32)
        skip = self._scratch("skip", shape, np.int32)
        per_row = self._scratch("per_row", (fac.height, 4), np.int64)
        geom = SlabGeometry(values, classified.has_nan, order, slab_frac, planes, fac.alpha_a, fac.beta_a, fac.alpha_b,
                            fac.beta_b, _rows(fac.height), ROW_BLOCK, 1.0 / fac.spacing)  # fmt: skip
        termination = Termination(bool(opts["early_termination"]), float(opts["termination_alpha"]))
        clip = Clipping(limits is not None, clip_lo, clip_hi)

        def block(m0: int, m1: int) -> None:
            composite_classes(geom, m0, m1, rgba, front, stamp, skip, per_row, classification, halves, run_set,
                              termination, clip)  # fmt: skip

        self._blocks(progress, len(order), block)
        image = self._warp(rgba, fac, width, height, opts)
        totals = per_row.sum(axis=0)
        counters.update(samples=float(totals[0]), empty_pixels_skipped=float(totals[1]),
                        pixels_terminated=float(totals[2]))  # fmt: skip
        return image, counters

    def _blocks(
        self, progress: ProgressCallback | None, slices: int, run: Callable[[int, int], None]
    ) -> None:
        """Slices 1.. in blocks of about BLOCK_MS, progress after each (the callback may raise: it propagates)."""
        spent = 0.0
        count = (
            FIRST_BLOCKS
            if self._slab_ms is None
            else min(MAX_BLOCKS, max(1, round(self._slab_ms / BLOCK_MS)))
        )
        edges = np.unique(np.linspace(1, max(slices, 1), count + 1).round().astype(int))
        if len(edges) < 2:
            edges = np.array([1, max(slices, 1)])
        for m0, m1 in zip(edges[:-1], edges[1:], strict=False):
            old = numba.set_parallel_chunksize(ROW_CHUNK)
            start = time.perf_counter()
            try:
                run(int(m0), int(m1))
            finally:
                numba.set_parallel_chunksize(old)
            spent += time.perf_counter() - start
            if progress is not None:
                progress(float(m1) / max(slices, 1))
        if progress is not None and edges[-1] < slices:
            progress(1.0)
        self._slab_ms = spent * 1000.0

    @staticmethod
    def _warp(inter: NDArray[np.float32], fac: Factorization, width: int, height: int,
              opts: Mapping[str, Any]) -> NDArray[np.float32]:  # fmt: skip
        wm = fac.warp
        assert (wm.width, wm.height) == (width, height)
        return warp(
            inter,
            wm.homography,
            wm.sign,
            fac.origin_ab,
            fac.scale,
            width,
            height,
            opts["warp_filter"] == "cubic",
        )
