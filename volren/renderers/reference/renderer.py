"""The `reference` renderer: DESIGN.md's optical model integrated in float64 until it converges.

Why: every error in the project (benchmarks, renderer tests) is measured against this renderer,
so it favours accuracy over speed, and says so when it could not reach its tolerance.

How: one ray per pixel centre (`Camera.pixel_rays`: origins on the near plane), clipped to the far
plane as well. Uniform grids go through `uniform.render_uniform` (trilinear, per-cell cubics), meshes
through `tets.render_tets` (screen-space binning, exact ray-tetrahedron clipping); both hand their
per-ray intervals to `refinement.integrate_ray`, which refines each ray until two successive
levels agree to `tolerance` (see `ray_integral` for the quadrature). A 2D TF (uniform grids,
composite) is refined by the same rule with `tf2d`'s quadrature instead (the 2D TF is sampled,
not cut into linear pieces). The image is processed in blocks
of rows, one parallel numba kernel call per block, with `progress` called after each block.

Label volumes (a `LabelTransferFunction` on a uniform grid with a label map) go through
`labelled.render_labelled` instead: the same rays, clipping and blocks, each cell blending the TFs
of its corner labels (`volren.model.labels`), refined by the same rule; composite only, without
shading or cut faces (refused in one line). Multi-channel volumes (a `ChannelTransferFunction` on a
uniform grid with channels) go through `channels.render_channels` the same way, each point mixing
the channels' TFs of their own scalars (`volren.model.channels`), with the same refusals.

RenderSettings.jitter is ignored (the reference is deterministic) and preintegration is not
offered (the reference integrates the TF exactly; callers comparing against a pre-integrating
renderer render the reference with preintegration off).

Counters of a frame (`last_frame.counters`): samples (TF evaluations), rays, rays_hit, intervals
(cells or tetrahedra crossed, summed over rays), unconverged_rays, max_level and mean_level (over
the rays that hit data; level 0 is the initial step), subdivision_cap_hits, and for meshes
candidates (pixel-list entries) and flat_or_nonfinite_tets, for label volumes label_classes (the
distinct visible TFs), for channels channels_drawn (those visible with a weight > 0).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import replace
from typing import ClassVar

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError, VolrenWarning
from volren.kernels.ray_block import BinnedRays
from volren.kernels.row_blocks import run_in_row_blocks
from volren.kernels.shading import shade_params
from volren.kernels.tet_projection import bin_rows, projected_boxes, ray_far
from volren.kernels.tf_eval import pack_tf
from volren.model.camera import Camera
from volren.model.channels import ChannelTransferFunction
from volren.model.labels import LabelTransferFunction
from volren.model.settings import BlendMode
from volren.model.tet_mesh import prepare_mesh
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TransferFunction2D
from volren.model.volume import TetVolume, UniformVolume
from volren.renderers.base import (
    Accuracy,
    Capabilities,
    KindSupport,
    OptionSpec,
    ProgressCallback,
    QualityLevel,
    RendererBase,
)
from volren.renderers.reference.channels import render_channels
from volren.renderers.reference.label_classes import class_map, pack_classes, pack_tfs
from volren.renderers.reference.labelled import render_labelled
from volren.renderers.reference.ray_inputs import CellPlanes, GridBox, Quadrature
from volren.renderers.reference.ray_integral import AVERAGE, COMPOSITE, MAXIMUM, MINIMUM
from volren.renderers.reference.tets import render_tets
from volren.renderers.reference.tf2d import pack_tf2d
from volren.renderers.reference.uniform import render_uniform

DEFAULT_TOLERANCE = 1e-5
DEFAULT_MAX_LEVELS = 10
#: Rays per parallel work item: small, because ray costs vary a lot across the image.
CHUNK_SIZE = 4
#: Target number of row blocks (progress calls) per frame.
BLOCKS = 16

_MODES = {
    BlendMode.COMPOSITE: COMPOSITE,
    BlendMode.MAXIMUM: MAXIMUM,
    BlendMode.MINIMUM: MINIMUM,
    BlendMode.AVERAGE: AVERAGE,
}

_SUPPORT = KindSupport(
    tf_dims=frozenset({1}),
    preintegration=False,
    shading=True,
    blend_modes=frozenset(BlendMode),
    # the per-ray tolerance bounds the max abs error; the kit measures RMSE up to 2e-8 (float32
    # rounding) and the point 0.09 px off (the blob's own asymmetry in perspective)
    accuracy=Accuracy(rmse=DEFAULT_TOLERANCE, position_px=0.15),
    clip_region=True,
    clip_cap=True,
)
#: Uniform grids also take 2D TFs (composite only: `tf2d`), draw bricks (the ray clipped to the
#: brick's box: the integral is exact, so no sample anchoring is needed), label volumes
#: (`labelled`: composite, unshaded, no cut faces) and channels (`channels`: the same).
_UNIFORM_SUPPORT = replace(
    _SUPPORT,
    tf_dims=frozenset({1, 2}),
    blend_modes_2d=frozenset({BlendMode.COMPOSITE}),
    regions=True,
    labels=True,
    channels=True,
)


class ReferenceRenderer(RendererBase):
    """Float64 ray integration of DESIGN.md's optical model, refined per ray until converged."""

    name: ClassVar[str] = "reference"
    capabilities: ClassVar[Capabilities] = Capabilities(
        kinds={"uniform": _UNIFORM_SUPPORT, "tet": _SUPPORT},
        backend="cpu",
        summary="float64 ray integration refined until converged; the truth for error metrics",
        quality=(
            QualityLevel("tolerance 1e-3", options={"tolerance": 1e-3}),
            QualityLevel("tolerance 1e-4", options={"tolerance": 1e-4}),
            QualityLevel("tolerance 1e-5 (default)"),
        ),
    )
    options: ClassVar[tuple[OptionSpec, ...]] = (
        OptionSpec(
            "tolerance",
            DEFAULT_TOLERANCE,
            "float",
            "per-ray convergence tolerance, max abs RGBA change between levels",
            low=0.0,
            low_exclusive=True,
        ),
        OptionSpec(
            "max_levels",
            DEFAULT_MAX_LEVELS,
            "int",
            "most refinement levels per ray, each halving the step",
            low=2,
            high=24,
        ),
    )

    def __init__(self) -> None:
        super().__init__()
        self._prepared: tuple | None = None
        #: (the label classes' lookup table, the class of every grid point) of the last label frame
        self._class_map: tuple[NDArray[np.int32], NDArray[np.int32]] | None = None
        #: the volume's channels in float64 (c, z, y, x), kept while the volume stays
        self._channel_values: NDArray[np.float64] | None = None
        #: The last frame in float64 (H, W, 4), before rounding to float32: for exact tests.
        self.last_rgba64: NDArray[np.float64] | None = None

    # ------------------------------------------------------------------------- state
    def _volume_changed(self) -> None:
        self._prepared = None
        self._class_map = None
        self._channel_values = None

    def _prepare(self) -> tuple:
        if self._prepared is None:
            vol = self._volume
            if isinstance(vol, UniformVolume):
                values = np.ascontiguousarray(vol.values, dtype=np.float64)
                b = np.asarray(vol.bounds, dtype=np.float64)
                self._prepared = (
                    values,
                    np.asarray(vol.origin, dtype=np.float64),
                    np.asarray(vol.spacing, dtype=np.float64),
                    np.ascontiguousarray(b[0::2]),
                    np.ascontiguousarray(b[1::2]),
                    vol.characteristic_length,
                )
            else:
                assert isinstance(vol, TetVolume)
                self._prepared = (prepare_mesh(vol), vol.characteristic_length)
        return self._prepared

    # ------------------------------------------------------------------------ render
    def _render(
        self, camera: Camera, width: int, height: int, progress: ProgressCallback | None
    ) -> tuple[NDArray[np.float32], Mapping[str, float]]:
        if isinstance(self._tf, LabelTransferFunction):
            return self._render_labels(camera, width, height, progress)
        if isinstance(self._tf, ChannelTransferFunction):
            return self._render_channels(camera, width, height, progress)
        vol = self._volume
        settings = self._settings
        tol, max_levels = self.opts["tolerance"], self.opts["max_levels"]
        mode = _MODES[settings.blend_mode]
        given = self._tf
        assert isinstance(given, TransferFunction1D | TransferFunction2D)  # the base class checked it
        two_d = isinstance(given, TransferFunction2D)
        tf = pack_tf2d(given) if isinstance(given, TransferFunction2D) else pack_tf(given)
        prepared = self._prepare()
        length = prepared[-1]
        region = self._region
        lo, hi = self._whole_value_range()
        spar = shade_params(settings, camera, hi - lo, length)
        h0 = float(settings.step) * length
        quad = Quadrature(mode, h0, tol, max_levels)

        origins, dirs = camera.pixel_rays(width, height)
        origins = np.ascontiguousarray(origins.reshape(-1, 3))
        dirs = np.ascontiguousarray(dirs.reshape(-1, 3))
        tfar = np.ascontiguousarray(ray_far(camera, dirs))
        n = width * height
        out = np.zeros((n, 4))
        stats = np.zeros((n, 5), np.int64)
        extra: dict[str, float] = {}
        clip = settings.clip.half_spaces()
        caps = settings.clip.caps and mode == _MODES[BlendMode.COMPOSITE]
        if caps and two_d:
            raise VolrenError("reference: cut faces (clip caps) need a 1D transfer function")

        if isinstance(vol, UniformVolume):
            values, org, sp, blo, bhi, _ = prepared
            if region is not None:  # the brick's own box: the integral is exact, so cutting it there is too
                blo, bhi = region.box

        if isinstance(vol, UniformVolume):
            tf_1d, tf_2d = (None, tf) if two_d else (tf, None)
            grid = GridBox(values, org, sp, blo, bhi, clip, caps)

            def kernel(a: int, b: int) -> None:
                render_uniform(
                    origins[a:b], dirs[a:b], tfar[a:b], grid, tf_1d, tf_2d, spar, quad, out[a:b], stats[a:b]
                )

        else:
            mesh, _ = prepared
            p = mesh.planes
            cells = CellPlanes(p.normals, p.anchors, p.sigma, p.values, p.gradients)
            boxes = projected_boxes(camera, width, height, mesh.points, mesh.tets, p.usable)
            extra["candidates"] = 0.0
            extra["flat_or_nonfinite_tets"] = float(np.count_nonzero(~p.usable))

            def kernel(a: int, b: int) -> None:
                offsets, cand = bin_rows(boxes, width, a // width, b // width)
                extra["candidates"] += len(cand)
                render_tets(BinnedRays(origins[a:b], dirs[a:b], tfar[a:b], offsets, cand, clip, caps), cells, tf, spar, quad,
                            out[a:b], stats[a:b])  # fmt: skip

        run_in_row_blocks(width, height, BLOCKS, CHUNK_SIZE, kernel, progress)
        return self._finish(out, stats, width, height, extra)

    def _render_labels(
        self, camera: Camera, width: int, height: int, progress: ProgressCallback | None
    ) -> tuple[NDArray[np.float32], Mapping[str, float]]:
        """A label volume through `labelled.render_labelled` (the base class has checked that the
        volume is a uniform grid with labels)."""
        tf, settings, vol = self._tf, self._settings, self._volume
        assert (
            isinstance(tf, LabelTransferFunction)
            and isinstance(vol, UniformVolume)
            and vol.labels is not None
        )
        if settings.shade:
            raise VolrenError("reference: shading is not drawn with label volumes; set shade off")
        if settings.blend_mode != BlendMode.COMPOSITE:
            raise VolrenError(
                f"reference: label volumes are drawn with the composite blend mode only, not {settings.blend_mode}"
            )
        if settings.clip.caps:
            raise VolrenError("reference: cut faces (clip caps) are not drawn with label volumes")
        values, org, sp, blo, bhi, length = self._prepare()
        if self._region is not None:  # the brick's own box, as for plain TFs
            blo, bhi = self._region.box
        labels = vol.labels
        classes = tf.classes(labels.max_label)
        # the class of every point, a volume-sized array, is kept while the labels' classes stay
        if self._class_map is None or not np.array_equal(self._class_map[0], classes.lookup):
            self._class_map = (classes.lookup, class_map(labels, classes.lookup))
        classes_at = self._class_map[1]
        packed = pack_classes(classes)
        quad = Quadrature(_MODES[BlendMode.COMPOSITE], float(settings.step) * length, self.opts["tolerance"],
                          self.opts["max_levels"])  # fmt: skip
        grid = GridBox(values, org, sp, blo, bhi, settings.clip.half_spaces(), False)

        origins, dirs, tfar = self._rays(camera, width, height)
        n = width * height
        out = np.zeros((n, 4))
        stats = np.zeros((n, 5), np.int64)

        def kernel(a: int, b: int) -> None:
            render_labelled(
                origins[a:b], dirs[a:b], tfar[a:b], grid, classes_at, packed, quad, out[a:b], stats[a:b]
            )

        run_in_row_blocks(width, height, BLOCKS, CHUNK_SIZE, kernel, progress)
        return self._finish(
            out, stats, width, height, {"label_classes": float(len(classes.tfs))}, stacklevel=5
        )

    def _render_channels(
        self, camera: Camera, width: int, height: int, progress: ProgressCallback | None
    ) -> tuple[NDArray[np.float32], Mapping[str, float]]:
        """A multi-channel volume through `channels.render_channels` (the base class has checked
        that the volume is a uniform grid with as many channels as the TF)."""
        tf, settings, vol = self._tf, self._settings, self._volume
        assert isinstance(tf, ChannelTransferFunction) and isinstance(vol, UniformVolume)
        assert vol.channels is not None
        if settings.shade:
            raise VolrenError("reference: shading is not drawn with channels; set shade off")
        if settings.blend_mode != BlendMode.COMPOSITE:
            raise VolrenError(
                f"reference: channels are drawn with the composite blend mode only, not {settings.blend_mode}"
            )
        if settings.clip.caps:
            raise VolrenError("reference: cut faces (clip caps) are not drawn with channels")
        _, org, sp, blo, bhi, length = self._prepare()
        if self._region is not None:  # the brick's own box, as for plain TFs
            blo, bhi = self._region.box
        if self._channel_values is None:
            self._channel_values = np.ascontiguousarray(vol.channels.values, dtype=np.float64)
        drawn = np.array([c for c in range(tf.count) if tf.drawn_weight(c) > 0.0], dtype=np.int64)
        tfs = pack_tfs([tf.tfs[c] for c in drawn])
        weights = np.array([tf.drawn_weight(c) for c in drawn], dtype=np.float64)
        quad = Quadrature(_MODES[BlendMode.COMPOSITE], float(settings.step) * length, self.opts["tolerance"],
                          self.opts["max_levels"])  # fmt: skip
        # the walk only needs the grid's cells: a read-only grid of zeros, no volume-sized copy
        cells = np.broadcast_to(np.zeros(1), vol.channels.shape)
        grid = GridBox(cells, org, sp, blo, bhi, settings.clip.half_spaces(), False)
        values = self._channel_values

        origins, dirs, tfar = self._rays(camera, width, height)
        n = width * height
        out = np.zeros((n, 4))
        stats = np.zeros((n, 5), np.int64)

        def kernel(a: int, b: int) -> None:
            render_channels(origins[a:b], dirs[a:b], tfar[a:b], grid, values, drawn, tfs, weights, quad, out[a:b],
                            stats[a:b])  # fmt: skip

        run_in_row_blocks(width, height, BLOCKS, CHUNK_SIZE, kernel, progress)
        return self._finish(out, stats, width, height, {"channels_drawn": float(len(drawn))}, stacklevel=5)

    @staticmethod
    def _rays(
        camera: Camera, width: int, height: int
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """One ray per pixel centre, row by row: (origins (n, 3), directions (n, 3), far-plane parameters)."""
        origins, dirs = camera.pixel_rays(width, height)
        origins = np.ascontiguousarray(origins.reshape(-1, 3))
        dirs = np.ascontiguousarray(dirs.reshape(-1, 3))
        return origins, dirs, np.ascontiguousarray(ray_far(camera, dirs))

    def _finish(
        self,
        out: NDArray[np.float64],
        stats: NDArray[np.int64],
        width: int,
        height: int,
        extra: dict[str, float],
        stacklevel: int = 4,
    ) -> tuple[NDArray[np.float32], Mapping[str, float]]:
        """The frame from the rays' float64 RGBA and statistics: the image, its counters, and a
        warning when rays did not converge (at `stacklevel`: the caller of `render`)."""
        tol, max_levels = self.opts["tolerance"], self.opts["max_levels"]
        n = width * height
        # only rounding can take a channel out of [0, 1] or rgb above alpha: clamp that
        rgba = np.clip(out, 0.0, 1.0)
        rgba[:, :3] = np.minimum(rgba[:, :3], rgba[:, 3:4])
        self.last_rgba64 = rgba.reshape(height, width, 4)
        image = self.last_rgba64.astype(np.float32)

        hit = stats[:, 4] > 0
        unconverged = int(stats[:, 2].sum())
        counters: dict[str, float] = {
            "samples": float(stats[:, 0].sum()),
            "rays": float(n),
            "rays_hit": float(np.count_nonzero(hit)),
            "intervals": float(stats[:, 4].sum()),
            "unconverged_rays": float(unconverged),
            "max_level": float(stats[:, 1].max(initial=0)),
            "mean_level": float(stats[hit, 1].mean()) if hit.any() else 0.0,
            "subdivision_cap_hits": float(stats[:, 3].sum()),
            "tolerance": tol,
            **extra,
        }
        if unconverged:
            warnings.warn(
                f"reference renderer: {unconverged} of {n} rays did not converge to {tol:g} "
                f"within {max_levels} levels (their finest level is used)",
                VolrenWarning,
                stacklevel=stacklevel,
            )
        return image, counters
