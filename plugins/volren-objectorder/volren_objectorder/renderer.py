"""`objectorder`: object-order ray casting (Mora, Jessel and Caubet 2002) with a min-max octree and
hidden volume removal through a hierarchical occlusion map, on the CPU with numba.

Why: a ray caster loads the eight corners of a cell again for every ray and every sample that
falls in it; object order loads each visible cell once and samples all the rays of its footprint
there, at exactly a ray caster's evenly spaced positions (depth indicators), with trilinear
interpolation and post-classification (or pre-integration). Empty space is skipped by a min-max
octree that is reclassified, not rebuilt, on TF edits, and hidden volume by an occlusion pyramid
over the image. It is built only on volren's public contract (volren.model, volren.renderers.base,
volren.model.preintegration), the way a third party would.

How a frame goes (module per step):
1. `patterns`: every pixel's ray in grid-index space, its entry, sample count and depth offset.
2. `octree`: the visibility pyramid for this TF (cached; dilated for pre-integration).
3. `composite`: bands of rows in parallel, each walking the octree front to back (`traversal`),
   skipping transparent nodes and nodes on finished pixels (`occlusion`), sampling leaf cells.

Label volumes and multi-channel volumes (a `LabelTransferFunction`, a `ChannelTransferFunction`) are
drawn by the same walk with volren's shared sample kernels (`mixed_samples`) over an octree classified
by their TFs (`mixed_classes`): composite, post-classified, unshaded.

Perspective is exact too: each pixel keeps its own ray (no shared templates), and the octree's
child order is taken per node from the side of its split planes the eye is on.

Counters (Mora et al.'s Table 1): cells (leaf cells neither transparent nor occluded), cells_occluded
(non-transparent cells under skipped nodes), occluded_ratio, nodes (octree nodes visited),
nodes_occluded, samples, cells_visible (non-transparent cells in the volume), pixels_saturated,
rays, bands. Node and cell counts are per band of rows, each node counted by the band holding the
middle row of its footprint.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, ClassVar

import numba
import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError
from volren.kernels.mixed_inputs import ChannelClassification, LabelClassification
from volren.kernels.sample_placement import pixel_phases
from volren.kernels.shading import ShadeParams, gradient_threshold
from volren.model import BlendMode, Camera, TransferFunction1D, UniformVolume
from volren.model.channels import ChannelTransferFunction
from volren.model.labels import LabelTransferFunction
from volren.model.preintegration import lighting_tables, preintegrate
from volren.model.settings import check_step
from volren.model.volume import spanning
from volren.renderers.base import (
    Accuracy,
    Capabilities,
    KindSupport,
    OptionRule,
    OptionSpec,
    ProgressCallback,
    QualityLevel,
    RendererBase,
)
from volren_objectorder import composite as K
from volren_objectorder.bundles import Compositing, Grid, Octree, PixelState, Rays, Tables, View
from volren_objectorder.mixed_classes import MixedClasses
from volren_objectorder.mixed_samples import PLAIN
from volren_objectorder.octree import Classification, MinMaxOctree, Reach
from volren_objectorder.patterns import (
    OFFSET_MODES,
    RayTable,
    direction_signs,
    ray_table,
    screen_matrix,
)

#: 0 (classify every sample exactly) or a table of 16 entries or more.
CLASSIFICATION_TABLE_RULE = OptionRule(lambda n: n == 0 or 16 <= n <= 65536, "0 or an integer in 16..65536")
OPTIONS: tuple[OptionSpec, ...] = (
    OptionSpec(
        "octree_skipping",
        True,
        "bool",
        "skip octree nodes the TF makes transparent (the image is the same, except where a pre-integration "
        "table too coarse for the TF leaks opacity into values the TF makes transparent: skipped, that leak "
        "is left out)",
    ),
    OptionSpec(
        "hidden_volume_removal",
        True,
        "bool",
        "stop pixels at termination_alpha and skip octree nodes whose footprint lies on finished pixels "
        "(hierarchical occlusion map; composite only)",
    ),
    OptionSpec(
        "termination_alpha", 0.999, "float", "opacity at which a pixel counts as opaque", low=0.5, high=1.0
    ),
    OptionSpec(
        "depth_offsets",
        "interleaved",
        "choice",
        "where each pixel's sample segments start, each sampled at its middle: 'interleaved' (phase 0 and 1/2 "
        "of a step on a checkerboard, the seed's), 'midpoint' (all on the same planes), 'random' (seeded; "
        "also the jitter setting)",
        choices=OFFSET_MODES,
    ),
    OptionSpec("jitter_seed", 0, "int", "seed of the random depth offsets", low=0, high=2**63 - 1),
    OptionSpec("table_size", 256, "int", "entries per axis of the pre-integration table", low=16, high=4096),
    OptionSpec(
        "classification_table",
        4096,
        "int",
        "entries of the post-classification table, colour and opacity per full step (0: classify every "
        "sample exactly, a search and an exp and a log each; label and channel tables then take 4096)",
        rule=CLASSIFICATION_TABLE_RULE,
    ),
    OptionSpec(
        "band_rows",
        32,
        "int",
        "image rows per parallel band (smaller bands are used for small images)",
        low=1,
        high=4096,
    ),
    OptionSpec(
        "block_pixels",
        36,
        "int",
        "draw the 2 x 2 x 2 cells under an octree node as one block (one footprint, one load of their 27 grid "
        "points, one slab test per pixel) when its footprint has at most this many pixels, none of them "
        "finished, and 4 of its cells or more are visible; compositing only; the image is the same (0: cell "
        "by cell)",
        low=0,
        high=65536,
    ),
)

_MODES = {BlendMode.COMPOSITE: K.COMPOSITE, BlendMode.MAXIMUM: K.MAXIMUM, BlendMode.MINIMUM: K.MINIMUM,
          BlendMode.AVERAGE: K.AVERAGE}  # fmt: skip


def segment_reach(
    camera: Camera, volume: UniformVolume, rays: RayTable, h: float, clipped: bool = False
) -> Reach:
    """The cells a pre-integrated segment ending in a cell can take its values from this frame: a
    segment's front lies up to h back along its ray, so along an axis the window runs toward
    lower indices only where every ray runs toward higher ones (and the other way round); the faces
    the rays leave through get the box both ways (a last sample's piece runs on to the exit point),
    and so does every cell when the far plane cuts the volume (rays then end inside it) or when a
    step spans more than one cell along an axis, and when a clip region cuts the rays (they end inside the
    volume wherever a plane lies: both ways whatever the planes, so moving one keeps the classification)."""
    cells = tuple(int(math.ceil(h / s - 1e-9)) for s in volume.spacing)
    if max(cells) > 1:
        # a step longer than a cell (anisotropic spacing, coarse steps): the rim's brute-force box
        # would grow with the step cubed (spacing 1:100 at step 0.5: boxes of 3 x 3 x 69 cells on
        # most of the grid), the separable dilation both ways does not
        return Reach.both_ways(cells)  # type: ignore[arg-type]
    if clipped or camera.depth_range(volume.bounds)[1] >= camera.clipping_range[1]:
        return Reach.both_ways(cells)  # type: ignore[arg-type]
    rising, falling = direction_signs(rays.direction, rays.count)
    window = tuple((c if up else 0, c if down else 0) for c, up, down in zip(cells, rising, falling))
    rim = tuple((c + 1 if down else 0, c + 1 if up else 0) for c, up, down in zip(cells, rising, falling))
    return Reach(window, rim)  # type: ignore[arg-type]


def _read_only(array: np.ndarray) -> np.ndarray:
    """A read-only view of `array` (for one numba type per table argument)."""
    view = array.view()
    view.flags.writeable = False
    return view


class ObjectOrderRenderer(RendererBase):
    """Object-order ray casting on uniform grids: composite, maximum, minimum, average, shading,
    pre-integration; parallel and perspective; label and multi-channel volumes (composite)."""

    name: ClassVar[str] = "objectorder"
    capabilities: ClassVar[Capabilities] = Capabilities(
        kinds={
            "uniform": KindSupport(
                tf_dims=frozenset({1}),
                preintegration=True,
                shading=True,
                blend_modes=frozenset(BlendMode),
                # measured with the full kit (docs/conformance/objectorder.txt): RMSE up to 0.011 (the
                # NaN box: a sample next to the NaN cells stands for its whole step), 0.0063 elsewhere
                # (the ramp), the point 0.024 px off
                accuracy=Accuracy(rmse=0.02, position_px=0.05),
                clip_region=True,
                labels=True,  # composite, post-classified, unshaded (`mixed_samples`)
                labels_preintegration=False,
                channels=True,  # composite, post-classified, unshaded (`mixed_samples`)
            )
        },
        backend="cpu",
        summary="object-order ray casting (numba): min-max octree, hidden volume removal, exact ray-caster samples",
        quality=(
            QualityLevel("step 1", step=1.0, preintegration=False),
            QualityLevel("step 1, pre-integrated", step=1.0, preintegration=True),
            QualityLevel("step 0.5 (default)", step=0.5, preintegration=False),
            QualityLevel("step 0.5, pre-integrated", step=0.5, preintegration=True),
            # post-classified at a quarter step: on sharp TFs as accurate as pre-integration at half a
            # step and cheaper (no table lookup per sample; docs/bench/quality.md)
            QualityLevel("step 0.25", step=0.25, preintegration=False),
            QualityLevel("step 0.25, pre-integrated", step=0.25, preintegration=True),
        ),
    )
    options: ClassVar[tuple[OptionSpec, ...]] = OPTIONS

    def __init__(self) -> None:
        super().__init__()
        self._octree: MinMaxOctree | None = None
        self._phases: tuple[tuple[str, int, int, int], NDArray[np.float64]] | None = None
        self._rays: RayTable | None = None
        self._buffers: dict[str, NDArray[Any]] = {}
        self._mixed = MixedClasses()

    # ------------------------------------------------------------------------- state
    def _volume_changed(self) -> None:
        volume = self.volume
        assert isinstance(volume, UniformVolume)
        self._octree = MinMaxOctree(volume)
        self._mixed = MixedClasses()

    def release(self) -> None:
        self._octree = None
        self._rays = None
        self._buffers = {}
        self._mixed = MixedClasses()
        super().release()

    def _buffer(self, name: str, shape: tuple[int, ...], dtype: type) -> NDArray[Any]:
        """A per-pixel array kept from frame to frame (contents undefined), new when the size changes."""
        found = self._buffers.get(name)
        if found is None or found.shape != shape or found.dtype != dtype:
            found = np.empty(shape, dtype)
            self._buffers[name] = found
        return found

    def _offsets(self, mode: str, width: int, height: int, seed: int) -> NDArray[np.float64]:
        """The pixels' phases, kept while the mode and image size stay (a frame's worth of numpy)."""
        key = (mode, width, height, seed)
        if self._phases is None or self._phases[0] != key:
            self._phases = (key, pixel_phases(mode, width, height, seed))
        return self._phases[1]

    @property
    def octree(self) -> MinMaxOctree | None:
        """The min-max octree of the current volume (for measurements and tests)."""
        return self._octree

    # ------------------------------------------------------------------------ render
    def _classification(self, tf: TransferFunction1D, composite: bool, skipping: bool, pre: bool, h: float,
                        camera: Camera, rays: RayTable) -> Classification:  # fmt: skip
        octree = self._octree
        assert octree is not None
        if not (composite and skipping):
            return octree.classify(None)
        volume = self.volume
        assert isinstance(volume, UniformVolume)
        clipped = not self.settings.clip.is_empty
        return octree.classify(tf, segment_reach(camera, volume, rays, h, clipped) if pre else Reach())

    def _mixed_classes(
        self, tf: LabelTransferFunction | ChannelTransferFunction, h: float
    ) -> tuple[LabelClassification | ChannelClassification, Classification]:
        """(the shared kernels' classification, the octree's visible cells) of a label or channel frame:
        composite, post-classified and unshaded only (refused otherwise, in one line, before any work)."""
        settings = self.settings
        what = "label volumes" if isinstance(tf, LabelTransferFunction) else "channels"
        if settings.blend_mode != BlendMode.COMPOSITE:
            raise VolrenError(f"objectorder: {what} are drawn composite only, not with {settings.blend_mode}")
        if settings.shade:
            raise VolrenError(f"objectorder: shading is not drawn with {what}; set shade off")
        volume = self.volume
        octree = self._octree
        assert isinstance(volume, UniformVolume) and octree is not None
        entries = int(self.opts["classification_table"])
        classes: LabelClassification | ChannelClassification
        if isinstance(tf, LabelTransferFunction):
            classes, cls = self._mixed.labels(volume, tf, h, entries, octree)
        else:
            classes, cls = self._mixed.channels(volume, tf, h, entries, octree)
        if not self.opts["octree_skipping"]:  # every cell (the kernels leave non-finite values out)
            cls = octree.classify_cells(("every",), lambda: np.ones(octree.cell_shape, np.uint8))
        return classes, cls

    def _render(
        self, camera: Camera, width: int, height: int, progress: ProgressCallback | None
    ) -> tuple[NDArray[np.float32], Mapping[str, float]]:
        volume = self.volume
        given = self.transfer_function
        assert isinstance(volume, UniformVolume)
        assert isinstance(given, TransferFunction1D | LabelTransferFunction | ChannelTransferFunction)
        assert self._octree is not None
        settings = self.settings
        opts = self.opts
        check_step(settings.step, volume.bounds, volume.characteristic_length)
        classes: Any = PLAIN
        mixed: tuple[LabelClassification | ChannelClassification, Classification] | None = None
        if not isinstance(given, TransferFunction1D):  # labels or channels: their own tables and cells
            mixed = self._mixed_classes(given, float(settings.step * volume.characteristic_length))
            classes = mixed[0]
        # a label or channel frame reads none of the 1D tables below: they are made for one of its TFs
        tf = given if isinstance(given, TransferFunction1D) else (
            given.base if isinstance(given, LabelTransferFunction) else given.tfs[0])  # fmt: skip
        h = float(settings.step * volume.characteristic_length)
        mode = _MODES[settings.blend_mode]
        composite = mode == K.COMPOSITE
        pre = bool(settings.preintegration) and composite
        shade = bool(settings.shade) and composite
        hvr = bool(opts["hidden_volume_removal"]) and composite

        offset_mode = "random" if settings.jitter else opts["depth_offsets"]
        origin = np.asarray(volume.origin, dtype=np.float64)
        planes = settings.clip.half_spaces_in_grid(origin, np.asarray(volume.spacing, dtype=np.float64))
        rays = ray_table(camera, volume, width, height, h, self._offsets(offset_mode, width, height, opts["jitter_seed"]),
                         self._rays, planes)  # fmt: skip
        self._rays = rays
        if mixed is None:
            cls = self._classification(tf, composite, bool(opts["octree_skipping"]), pre, h, camera, rays)
        else:
            cls = mixed[1]
        M = screen_matrix(camera, volume, width, height)
        spacing = np.asarray(volume.spacing, dtype=np.float64)
        eye = (np.asarray(camera.position, dtype=np.float64) - np.asarray(volume.origin)) / spacing
        vdir = np.asarray(camera.direction, dtype=np.float64) / spacing

        # the TF, exactly: colour and opacity at every breakpoint, linear between them
        xs = tf.breakpoints()
        rgb, a = tf.sample(xs)
        tab = np.ascontiguousarray(np.concatenate([rgb, a[:, None]], axis=1), dtype=np.float64)
        vlo, vhi = volume.value_range
        tlo, thi = tf.value_range
        lo, hi = min(vlo, tlo), max(vhi, thi)
        lo, hi = spanning(lo, hi)
        n = int(opts["table_size"])
        empty4 = np.zeros((2, 2, 4), np.float32)
        table, front, back = empty4, empty4, empty4
        if pre and shade:
            lit = lighting_tables(tf, n, step=h, value_range=(lo, hi))
            front, back = lit.front, lit.back
        elif pre:
            table = preintegrate(tf, n, step=h, value_range=(lo, hi))
        # all read-only, as the cached tables are: numba compiles a kernel once per combination of
        # writable and read-only arrays, and the mixed ones had tripled the plugin's compile time
        table, front, back = (_read_only(t) for t in (table, front, back))
        post = np.zeros((1, 4))  # one row: no table, every sample classified exactly
        n_post = int(opts["classification_table"])
        if composite and not pre and n_post and mixed is None:
            rgb, a = tf.sample(np.linspace(lo, hi, n_post))
            alpha = -np.expm1(h / tf.opacity_unit_distance * np.log1p(-np.minimum(a, K.MAX_OPACITY)))
            post = np.ascontiguousarray(np.concatenate([rgb, alpha[:, None]], axis=1), dtype=np.float64)
        light = -np.asarray(camera.direction, dtype=np.float64)
        inv_spacing = 1.0 / spacing
        tables = Tables(xs, tab, post, table, front, back, float(lo), float((n - 1) / (hi - lo)), float(lo),
                        float((len(post) - 1) / (hi - lo)))  # fmt: skip
        term = float(opts["termination_alpha"]) if hvr else 2.0  # 2: never, without hidden volume removal
        frame = Compositing(int(mode), bool(pre), bool(hvr), int(opts["block_pixels"]), float(h),
                            float(tf.opacity_unit_distance), term)  # fmt: skip
        shading = ShadeParams(bool(shade), float(settings.ambient), float(settings.diffuse), float(settings.specular),
                              float(settings.specular_power),
                              float(gradient_threshold(vhi - vlo, volume.characteristic_length)),
                              float(light[0]), float(light[1]), float(light[2]))  # fmt: skip

        pixels = width * height
        # per-pixel state, kept across frames (no page faults on fresh memory); rgba, nextk and
        # finished are cleared by each band in the kernel; what a mode never reads is one element long
        rgba = self._buffer("rgba", (pixels, 4), np.float64)
        nextk = self._buffer("nextk", (pixels,), np.int32)
        finished = self._buffer("finished", (pixels,), np.uint8)
        acc = self._buffer("acc", (pixels if not composite else 1, 2), np.float64)
        acc[:, 0] = -np.inf if mode == K.MAXIMUM else (np.inf if mode == K.MINIMUM else 0.0)
        acc[:, 1] = 0.0
        n_pre = pixels if pre else 1
        prev_k = self._buffer("prev_k", (n_pre,), np.int32)
        prev_s = self._buffer("prev_s", (n_pre,), np.float64)
        prev_fd = self._buffer("prev_fd", (n_pre,), np.float64)
        prev_sp = self._buffer("prev_sp", (n_pre,), np.float64)
        prev_k.fill(-1)
        prev_s.fill(0.0)
        prev_fd.fill(1.0)
        prev_sp.fill(0.0)

        threads = numba.get_num_threads()
        band_rows = int(min(opts["band_rows"], max(8, math.ceil(height / (4 * threads)))))
        n_bands = math.ceil(height / band_rows)
        stats = np.zeros((n_bands, K.N_STATS))
        # bands are taken one at a time by whichever thread is free (their costs differ widely);
        # a group per progress call, large enough that no thread idles at a group's end for long
        group = max(16, 8 * threads)
        order = np.arange(n_bands, dtype=np.int64)
        grid = Grid(self._octree.values, int(cls.shapes[0, 2]), int(cls.shapes[0, 1]), int(cls.shapes[0, 0]),
                    float(inv_spacing[0]), float(inv_spacing[1]), float(inv_spacing[2]))  # fmt: skip
        octree = Octree(cls.counts, cls.offsets, cls.shapes, cls.leaves)
        view = View(M, not camera.parallel, eye, vdir, width, height)
        ray_set = Rays(rays.origin, rays.direction, rays.world_direction, rays.inverse, rays.t0, rays.count, rays.first,
                       rays.last)  # fmt: skip
        state = PixelState(rgba, acc, nextk, prev_s, prev_k, prev_fd, prev_sp, finished)
        for g0 in range(0, n_bands, group):
            bands = order[g0 : g0 + group]
            old = numba.set_parallel_chunksize(1)
            try:
                K.render_bands(bands, band_rows, grid, octree, view, ray_set, tables, frame, shading, state, stats,
                               classes)  # fmt: skip
            finally:
                numba.set_parallel_chunksize(old)
            if progress is not None:
                progress(min(1.0, (g0 + len(bands)) / n_bands))

        if composite:
            image = np.empty((height, width, 4), np.float32)
            K.finish(rgba, image.reshape(-1, 4))
        else:
            hit = acc[:, 1] > 0
            value = np.where(hit, acc[:, 0], 0.0)
            if mode == K.AVERAGE:
                value = np.where(hit, value / np.where(hit, acc[:, 1], 1.0), 0.0)
            rgb, a = tf.sample(value)
            a = np.where(hit, a, 0.0)
            out = np.concatenate([rgb * a[:, None], a[:, None]], axis=1)
            out = np.clip(out, 0.0, 1.0)
            out[:, :3] = np.minimum(out[:, :3], out[:, 3:4])
            image = out.reshape(height, width, 4).astype(np.float32)

        totals = stats.sum(axis=0)
        cells, occluded = float(totals[K.S_CELLS]), float(totals[K.S_OCCLUDED_CELLS])
        counters = {
            "cells": cells, "cells_occluded": occluded,
            "occluded_ratio": occluded / (cells + occluded) if cells + occluded > 0 else 0.0,
            "nodes": float(totals[K.S_NODES]), "nodes_occluded": float(totals[K.S_OCCLUDED_NODES]),
            "samples": float(totals[K.S_SAMPLES]), "pixels_saturated": float(totals[K.S_SATURATED]),
            "cells_visible": float(cls.visible_cells), "rays": float(np.count_nonzero(rays.count)),
            "bands": float(n_bands),
        }  # fmt: skip
        return image, counters
