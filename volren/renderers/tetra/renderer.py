"""The `tetra` renderer: cell-to-cell ray casting through tetrahedral meshes (see `traversal`).

Per volume: `model.tet_mesh.prepare_mesh` (face adjacency and the face planes, bit-identical on
both sides of every face; cached by content hash). Per TF
version: the 3D pre-integration table over the mesh's value range and segment lengths up to its
longest edge (`model.preintegration`), turned into optical depth per unit length and colour per
unit opacity, the cells whose value range maps to zero opacity, and the boundary faces of the
visible cells, which composite rays walk alone (`walked_cells`). Per frame: the entry faces binned
to pixels, then the numba kernel over blocks of rows, or over the pixels adaptive refinement asks
for (`volren.kernels.image_refinement`), or the GL walk (`gl_walk`).

Counters: cell_steps (cells walked through, summed over rays), cells_integrated, rays_hit,
rays_cast, walks cut at max_steps, entries dropped (more boundary crossings along a ray than the
kernel keeps).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError
from volren.kernels.camera_rays import image_rays, pixel_rays
from volren.kernels.image_refinement import STRIDE_RULE, refine_image
from volren.kernels.ray_block import BinnedRays
from volren.kernels.row_blocks import parallel_chunk_size, run_in_row_blocks
from volren.kernels.shading import ShadeParams, shade_params
from volren.kernels.tet_planes import packed_face_planes
from volren.kernels.tet_projection import bin_rows, pixel_coordinates, ray_far
from volren.kernels.tf_eval import pack_tf
from volren.kernels.visible_ranges import visible_ranges
from volren.model.camera import Camera
from volren.model.preintegration import LengthAxis, preintegrate
from volren.model.settings import BlendMode
from volren.model.tet_mesh import PreparedMesh, prepare_mesh
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import TetVolume
from volren.renderers.base import (
    Accuracy,
    Capabilities,
    KindSupport,
    OptionSpec,
    ProgressCallback,
    QualityLevel,
    RendererBase,
)
from volren.renderers.tetra import walk_native
from volren.renderers.tetra.entry_bins import (
    TILE,
    EntryFaces,
    bin_tiles,
    bin_triangles,
    bin_triangles_at,
    gather_lists,
    merge_lists,
    project_faces,
)
from volren.renderers.tetra.gl_walk import GLWalk, WalkParameters, gl_mesh, gpu_renderer, near_plane_cells
from volren.renderers.tetra.optical_tables import optical_tables
from volren.renderers.tetra.traversal import (
    AVERAGE,
    COMPOSITE,
    MAXIMUM,
    MINIMUM,
    cast_rays,
)
from volren.renderers.tetra.walk_inputs import SegmentTable, TetCells, WalkedSet, WalkOptions
from volren.renderers.tetra.walked_cells import WalkedCells, walked_cells

_MODES = {
    BlendMode.COMPOSITE: COMPOSITE,
    BlendMode.MAXIMUM: MAXIMUM,
    BlendMode.MINIMUM: MINIMUM,
    BlendMode.AVERAGE: AVERAGE,
}
#: Row blocks per frame (progress calls).
BLOCKS = 8
#: Rays per parallel work item.
CHUNK_SIZE = 16


class TetraRenderer(RendererBase):
    """Ray casting from cell to cell through tetrahedral meshes, with 3D pre-integration."""

    name: ClassVar[str] = "tetra"
    capabilities: ClassVar[Capabilities] = Capabilities(
        kinds={
            "tet": KindSupport(
                preintegration=True,
                shading=True,
                blend_modes=frozenset(BlendMode),
                # kit (volren check-renderer tetra): RMSE up to 1.5e-6, the point 0.09 px off
                accuracy=Accuracy(rmse=1e-4, position_px=0.15),
                clip_region=True,
                clip_cap=True,
            )
        },
        backend="cpu/opengl",
        still_frame_options={"image_stride": 1},  # the app refines images in previews only
        summary="cell-to-cell ray casting through tetrahedra (numba, or compute shaders on a GPU) with 3D "
        "pre-integration tables",
        quality=(
            QualityLevel(
                "refine 64/1, table 64",
                options={"image_stride": 64, "refine_tolerance": 1.0, "table_size": 64},
            ),
            QualityLevel("refine 16/0.1", options={"image_stride": 16, "refine_tolerance": 0.1}),
            QualityLevel("table 64", options={"table_size": 64}),
            QualityLevel("table 256 (default)"),
            QualityLevel("table 512", options={"table_size": 512}),
        ),
        # a new TF rebuilds the 3D table: 289 -> 95 ms a 400x300 preview on oxygen (TF change + frame);
        # refining where neighbours differ by 0.1 (the draft level's) instead of 0.05: 95 -> 65 ms
        tf_drag_options={"table_size": 64, "table_lengths": 8, "refine_tolerance": 0.1},
    )
    options: ClassVar[tuple[OptionSpec, ...]] = (
        OptionSpec("table_size", 256, "int", "value entries per axis of the 3D table", low=2),
        OptionSpec("table_lengths", 32, "int", "segment-length layers of the 3D table", low=1),
        OptionSpec(
            "termination_alpha",
            0.999,
            "float",
            "opacity at which a ray stops (1 never stops early)",
            low=0.0,
            high=1.0,
            low_exclusive=True,
        ),
        OptionSpec(
            "max_steps", 100_000, "int", "most cells one walk may take before it is cut and counted", low=1
        ),
        OptionSpec(
            "skip_transparent",
            True,
            "bool",
            "skip cells whose value range the TF maps to zero opacity: composite rays jump from a "
            "transparent run to the next visible cell (false walks and integrates every cell, for comparison)",
        ),
        OptionSpec(
            "backend",
            "auto",
            "choice",
            "auto: the GL compute-shader walk on a hardware GPU, else numba on the CPU; cpu; gl (OpenGL 4.3 "
            "compute shaders, also on Mesa llvmpipe)",
            choices=("auto", "cpu", "gl"),
        ),
        OptionSpec(
            "image_stride",
            1,
            "int",
            "1: a ray through every pixel; 2 to 64 (a power of two): adaptive refinement, rays every "
            "`image_stride` pixels first, more only where neighbouring rays differ by more than "
            "refine_tolerance or at silhouettes, the rest interpolated (faster on smooth images; features "
            "thinner than the stride between rays that agree are missed; cpu backend)",
            rule=STRIDE_RULE,
        ),
        OptionSpec(
            "refine_tolerance",
            0.02,
            "float",
            "with image_stride > 1: the largest difference in any premultiplied RGBA channel between a "
            "block's corner rays that is interpolated instead of cast",
            low=0.0,
            high=1.0,
        ),
    )

    def __init__(self) -> None:
        super().__init__()
        self._mesh: PreparedMesh | None = None
        self._planes: tuple | None = None
        self._neighbor_faces: NDArray | None = None  # in the cells' Morton order, like _planes
        self._corner: NDArray | None = None
        self._records: walk_native.CellRecords | None = None  # the C walk's cells, built at its first frame
        self._table_key: tuple | None = None
        self._table: tuple | None = None
        self._cell_ranges: tuple[NDArray, NDArray, NDArray] | None = (
            None  # (the cells' corner values, lo, hi)
        )
        self._visible_walk: tuple[NDArray[np.bool_], WalkedCells] | None = (
            None  # (visible cells, their walk set)
        )
        self._walk_version = 0  # which walk set the GL walk's entry faces hold
        self._gl: GLWalk | None = None
        self._generation = 0  # which volume the GL walk's buffers hold

    def _volume_changed(self) -> None:
        self._mesh = None
        self._records = None
        self._planes = None
        self._table_key = None
        self._table = None
        self._cell_ranges = None
        self._visible_walk = None
        self._generation += 1

    def release(self) -> None:
        if self._gl is not None:
            self._gl.release()
            self._gl = None
        super().release()

    # ------------------------------------------------------------------------ preparation
    def _prepare(self) -> tuple[PreparedMesh, tuple]:
        """The mesh and, in Morton order, (tets, neighbours, the linear fields as (corner values
        (m, 4), gradients (m, 3)), packed planes, the usable cells as a `WalkedCells`)."""
        if self._mesh is None:
            volume = self._volume
            assert isinstance(volume, TetVolume)
            mesh = prepare_mesh(volume)
            # Cells in Morton order of their centroids: rays walk through neighbouring cells, and
            # neighbours then lie close in memory (docs/tetra-benchmark.md, "Cell order").
            order = _morton_order(mesh.points[mesh.tets].mean(axis=1))
            rank = np.empty_like(order)
            rank[order] = np.arange(len(order))
            tets = np.ascontiguousarray(mesh.tets[order], dtype=np.int64)
            old = mesh.neighbors[order]
            neighbors = np.ascontiguousarray(np.where(old >= 0, rank[np.maximum(old, 0)], -1), dtype=np.int64)
            self._neighbor_faces = np.ascontiguousarray(mesh.neighbor_faces[order], dtype=np.int64)
            # the planes of the ordered cells in one numba pass (`mesh.planes` and `pack_planes` in
            # numpy, then reordered, took 1.5 s of a one-shot render of oxygen)
            packed = walk_native.packed_planes(mesh.points, tets)
            if packed is None:
                packed = packed_face_planes(mesh.points, tets)
            usable_cells = np.ascontiguousarray(~(mesh.flat | mesh.nonfinite)[order])
            fields = (np.ascontiguousarray(mesh.values[tets]), np.ascontiguousarray(mesh.gradients[order]))
            # flat and non-finite cells are holes the rays step over to the next entry
            usable = walked_cells(usable_cells, tets, neighbors, packed)
            self._mesh = mesh
            self._planes = (tets, neighbors, fields, packed, usable)
            self._corner = np.ascontiguousarray(
                mesh.points[tets[:, 0]]
            )  # where each cell's linear field is anchored
        assert self._planes is not None
        return self._mesh, self._planes

    def _walked_cells(self, usable: WalkedCells, visible: NDArray[np.bool_] | None) -> WalkedCells:
        """The cells rays walk through: the usable ones, or (`visible` given) only those the TF
        makes visible, so that rays jump over transparent regions from exit to next entry instead
        of stepping through them cell by cell. Kept while the same cells are visible: most TF edits
        (a colour, an opacity that stays above zero, a peak moved inside its support) change the
        table but not the set, whose rebuild took 21 of a 91 ms TF-drag preview on oxygen."""
        if visible is None:
            return usable
        if self._visible_walk is None or not np.array_equal(self._visible_walk[0], visible):
            tets, neighbors, _, packed, _ = self._planes  # type: ignore[misc]
            self._visible_walk = (visible, walked_cells(usable.cells & visible, tets, neighbors, packed))
            self._walk_version += 1
        return self._visible_walk[1]

    @staticmethod
    def _on_plane(mesh: PreparedMesh) -> float:
        """A ray closer to a face plane than this (world units) lies in it: 1e-12 of the mesh's
        size, far below any cell and far above rounding in the plane equations."""
        b = np.asarray(mesh.bounds, dtype=np.float64)
        return 1e-12 * float(np.linalg.norm(b[1::2] - b[0::2]) + np.abs(b).max())

    def _entry_candidates(
        self, camera: Camera, width: int, height: int, mesh: PreparedMesh, tets: NDArray, walked: WalkedCells
    ) -> tuple[EntryFaces, NDArray[np.int64]]:
        """Where rays can enter the mesh: the boundary faces turned towards the eye, projected to
        pixels (`entry_bins`), and the cells the near plane cuts (pixel boxes by cell id, x0 = -1:
        none; no rows when it cuts none), where rays start inside the mesh."""
        cell, triangles, plane = walked.face_cells, walked.triangles, walked.face_planes
        if camera.parallel:
            facing = plane[:, :3] @ np.asarray(camera.direction) >= -1e-12
        else:
            eye = np.asarray(camera.position, dtype=np.float64)
            facing = plane[:, :3] @ eye + plane[:, 3] <= self._on_plane(mesh)
        px, py, w = pixel_coordinates(camera, width, height, mesh.points)
        faces = project_faces(px, py, ~(w > 0), triangles[facing], cell[facing], width, height)
        near_cells = np.zeros((0, 4), np.int64)
        cut = near_plane_cells(
            camera, width, height, mesh.points, tets, walked.cells, np.asarray(mesh.bounds)
        )
        if cut is not None:
            near_cells = np.full((len(tets), 4), -1, np.int64)
            near_cells[cut[0]] = cut[1]
        return faces, near_cells

    def _parse_options(self, options: Mapping[str, Any]) -> Mapping[str, Any]:
        """The options parsed; adaptive refinement runs on the cpu backend only."""
        opts = super()._parse_options(options)
        if opts["backend"] == "gl" and opts["image_stride"] > 1:
            raise VolrenError("renderer tetra: option image_stride > 1 runs on the cpu backend only (backend=cpu "
                              "or auto)")  # fmt: skip
        return opts

    def _cell_value_ranges(self) -> tuple[NDArray, NDArray]:
        """Each cell's lowest and highest corner value (NaN for a cell with no finite corner), kept
        for the mesh: TF edits reclassify with them (recomputing them cost each edit ~30 ms on oxygen)."""
        tvals = self._planes[2][0]  # type: ignore[index]
        if self._cell_ranges is None or self._cell_ranges[0] is not tvals:
            with warnings.catch_warnings():  # cells with no finite corner give NaN bounds, on purpose
                warnings.simplefilter("ignore", RuntimeWarning)
                self._cell_ranges = (tvals, np.nanmin(tvals, axis=1), np.nanmax(tvals, axis=1))
        return self._cell_ranges[1], self._cell_ranges[2]

    def _tables(self, mesh: PreparedMesh, n: int, layers: int) -> tuple:
        """(depth per length (n, n, 1), colour per opacity (K, n, n, 3), lo, scale, L_max, visible)."""
        tf = self._tf
        lo, hi = (float(v) for v in self._volume.value_range)  # type: ignore[union-attr]
        if not hi > lo:
            lo, hi = lo - 0.5, hi + 0.5
        lmax = float(mesh.max_edge_length)
        key = (tf.version, n, layers, lo, hi, lmax)  # type: ignore[union-attr]
        if key != self._table_key:
            axis = LengthAxis(lmax, layers)
            table = preintegrate(tf, n, lengths=axis.lengths, value_range=(lo, hi))
            depth, ratio = optical_tables(table, axis.lengths[0])
            cell_lo, cell_hi = self._cell_value_ranges()
            visible = _visible_cells(tf, cell_lo, cell_hi)
            self._table = (depth, ratio, lo, (n - 1) / (hi - lo), lmax, visible)
            self._table_key = key
        assert self._table is not None
        return self._table

    # ------------------------------------------------------------------------------ render
    def _uses_gl(self, opts: Mapping[str, Any]) -> bool:
        """The GL walk when asked for, or on `auto` with a ray per pixel and a
        hardware GPU (on Mesa llvmpipe numba keeps float64, progress per block of rows and adaptive
        refinement: `docs/tetra-benchmark.md`)."""
        caps = self.settings.clip.caps  # cut faces: on the CPU walk only
        if opts["backend"] == "auto":
            return opts["image_stride"] == 1 and not caps and gpu_renderer() is not None
        if opts["backend"] == "gl" and caps:
            raise VolrenError("renderer tetra: backend gl draws no cut faces (clip caps); use backend=cpu")
        return opts["backend"] == "gl"

    def _render(
        self, camera: Camera, width: int, height: int, progress: ProgressCallback | None
    ) -> tuple[NDArray[np.float32], Mapping[str, float]]:
        opts = self.opts
        start = time.perf_counter()
        mesh, (tets, neighbors, fields, packed, usable) = self._prepare()
        prepared = time.perf_counter()
        tvals, grads = fields
        depth, ratio, lo, scale, lmax, visible = self._tables(mesh, opts["table_size"], opts["table_lengths"])
        tabled = time.perf_counter()
        if not opts["skip_transparent"]:
            visible = np.ones_like(visible)
        transparent = float(np.count_nonzero(~visible))  # cells the walk skips or steps through unintegrated
        settings = self._settings
        mode = _MODES[settings.blend_mode]
        span = float(self._volume.value_range[1] - self._volume.value_range[0])  # type: ignore[union-attr]
        length = self._volume.characteristic_length  # type: ignore[union-attr]
        sp = shade_params(settings, camera, span, length)
        # transparent cells only matter to projections
        jump = opts["skip_transparent"] and mode == COMPOSITE
        walked = self._walked_cells(usable, visible if jump else None)
        if self._uses_gl(opts):
            walk = self._gl_walk(mesh, tets, neighbors, packed, tvals, grads, usable)
            walk.set_tables(
                (self._generation, self._table_key, opts["skip_transparent"]), depth[..., 0], ratio, visible
            )
            walk.set_entry_faces(
                (self._generation, self._walk_version if jump else None), walked, mesh.points
            )
            params = WalkParameters(mode, sp, lo, scale, lmax, float(opts["termination_alpha"]), int(opts["max_steps"]),
                                    jump, settings.clip.half_spaces())  # fmt: skip
            near = near_plane_cells(
                camera, width, height, mesh.points, tets, walked.cells, np.asarray(mesh.bounds)
            )
            out, counters = walk.render(camera, width, height, params, near)  # float32: no copy to float64
            counters.update(entries_dropped=0.0, rays_cast=float(width * height))
            rgba = self._pixels(out, mode)
            if progress is not None:
                progress(1.0)
        else:
            entries = self._entry_candidates(camera, width, height, mesh, tets, walked)
            assert self._corner is not None
            cells = TetCells(
                neighbors, packed, tvals, grads, self._corner, usable.cells, self._on_plane(mesh)
            )
            options = WalkOptions(mode, float(opts["termination_alpha"]), int(opts["max_steps"]))
            rgba, counters = self._render_cpu(camera, width, height, progress, opts, entries, cells,
                                              WalkedSet(walked.boundary, walked.cells, visible),
                                              SegmentTable(depth, ratio, lo, scale, lmax), options, sp)  # fmt: skip
        counters["cells_transparent"] = transparent
        # what this frame paid for its mesh and TF (0 when they were ready): `volren render --timings`
        counters["prepare_ms"] = 1000.0 * (prepared - start)
        counters["tables_ms"] = 1000.0 * (tabled - prepared)
        return rgba.reshape(height, width, 4).astype(np.float32, copy=False), counters

    def _pixels(self, out: NDArray, mode: int) -> NDArray:
        """Premultiplied RGBA (n, 4) from the walk's output: composites clipped to valid colours,
        projected values through the TF."""
        if mode == COMPOSITE:
            rgba = np.clip(out, 0.0, 1.0, out=out)
            np.minimum(rgba[:, :3], rgba[:, 3:4], out=rgba[:, :3])
            return rgba
        found = out[:, 1] > 0
        rgb, alpha = self._tf.sample(np.where(found, out[:, 0], np.nan))  # type: ignore[union-attr]
        return np.concatenate([rgb * alpha[:, None], alpha[:, None]], axis=1)

    def _gl_walk(
        self,
        mesh: PreparedMesh,
        tets: NDArray,
        neighbors: NDArray,
        packed: NDArray,
        tvals: NDArray,
        grads: NDArray,
        usable: WalkedCells,
    ) -> GLWalk:
        """The GL walk, holding this volume's mesh."""
        if self._gl is None:
            self._gl = GLWalk()
        if self._gl.mesh_key != self._generation:
            self._gl.set_mesh(
                self._generation,
                gl_mesh(
                    mesh.points, tets, neighbors, self._neighbor_faces, packed, tvals, grads, usable.cells
                ),
            )
        return self._gl

    def _render_cpu(self, camera: Camera, width: int, height: int, progress: ProgressCallback | None,
                    opts: Mapping[str, Any], entries: tuple[EntryFaces, NDArray[np.int64]], cells: TetCells,
                    walked: WalkedSet, table: SegmentTable, options: WalkOptions,
                    sp: ShadeParams) -> tuple[NDArray, dict[str, float]]:  # fmt: skip
        """The numba walk: (H * W, 4) premultiplied RGBA and the counters. A ray per pixel over
        blocks of rows, or with image_stride > 1 adaptive refinement (`image_refinement`); rays
        enter the mesh through the `entries` of `_entry_candidates`."""
        faces, near_cells = entries
        mode = options.mode
        totals = np.zeros(5, np.int64)  # cell steps, cells integrated, walks cut, entries dropped, rays hit
        clip = self.settings.clip.half_spaces()
        caps = self.settings.clip.caps
        tf = self.transfer_function
        assert isinstance(tf, TransferFunction1D)
        packed_tf = pack_tf(tf)
        in_c = walk_native.available(len(cells.neighbors))
        if in_c and self._records is None:
            self._records = walk_native.CellRecords(cells)
        records = self._records

        # the C walk finds each pixel's entry faces through these tile lists itself
        tiles = walk_native.FaceTiles(faces, *bin_tiles(faces), TILE) if in_c else None
        no_lists = no_lists_of(width * height)

        def walk(origins: NDArray, dirs: NDArray, offsets: NDArray, cand: NDArray, out: NDArray,
                 pixels: NDArray[np.int64]) -> NDArray:  # fmt: skip
            """The rays' walk output into `out` (n, 4); the counters summed into `totals`. numba's walk
            meets the cells listed per ray (offsets, cand); the C walk the cells of `pixels`' entry faces
            first, then those listed."""
            rays = BinnedRays(np.ascontiguousarray(origins), np.ascontiguousarray(dirs),
                              np.ascontiguousarray(ray_far(camera, dirs)), offsets, cand, clip, caps)  # fmt: skip
            if tiles is not None:
                assert records is not None
                walk_native.cast_rays(records, rays, cells, walked, table, packed_tf, options, sp, out, None, totals,
                                      tiles, pixels)  # fmt: skip
                return out
            stats = np.zeros((len(origins), 4), np.int64)
            cast_rays(rays, cells, walked, table, packed_tf, options, sp, out, stats)
            totals[:4] += stats.sum(axis=0)
            totals[4] += np.count_nonzero(stats[:, 0])
            return out

        def finished(out: NDArray) -> NDArray:
            """Premultiplied RGBA of the walk's output (the C walk clips composites itself)."""
            return out if tiles is not None and mode == COMPOSITE else self._pixels(out, mode)

        def near_lists(row0: int, row1: int) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
            """The cells the near plane cuts, listed per pixel of rows row0 .. row1 - 1."""
            if not len(near_cells):
                return no_lists[0][: (row1 - row0) * width + 1], no_lists[1]
            return bin_rows(near_cells, width, row0, row1)

        stride = opts["image_stride"]
        if stride == 1:
            origins, dirs = image_rays(camera, width, height)
            out = np.empty((width * height, 4))

            def rows(a: int, b: int) -> None:
                near = near_lists(a // width, b // width)
                lists = (
                    near
                    if tiles is not None
                    else merge_lists(*bin_triangles(faces, a // width, b // width), *near)
                )
                walk(origins[a:b], dirs[a:b], *lists, out[a:b], np.arange(a, b, dtype=np.int64))

            run_in_row_blocks(width, height, BLOCKS, CHUNK_SIZE, rows, progress)
            rgba, rays = finished(out), width * height
        else:
            near_all = near_lists(0, height) if len(near_cells) else None
            pixel_tiles = tiles[1:3] if tiles is not None else bin_tiles(faces)

            def cast(pixels: NDArray[np.int64]) -> NDArray:
                origins, dirs = pixel_rays(camera, width, height, pixels % width, pixels // width)
                near = gather_lists(*near_all, pixels) if near_all is not None else no_lists_of(len(pixels))
                if tiles is None:
                    near = merge_lists(*bin_triangles_at(faces, pixel_tiles, pixels), *near)
                return finished(walk(origins, dirs, *near, np.empty((len(pixels), 4)), pixels))

            with parallel_chunk_size(CHUNK_SIZE):
                rgba, rays = refine_image(
                    cast, width, height, stride, float(opts["refine_tolerance"]), progress
                )
        counters = {
            "cell_steps": float(totals[0]),
            "cells_integrated": float(totals[1]),
            "rays_hit": float(totals[4]),
            "rays_cast": float(rays),
            "walks_cut": float(totals[2]),
            "entries_dropped": float(totals[3]),
        }
        return rgba, counters


def no_lists_of(n: int) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Empty CSR lists of n pixels."""
    return np.zeros(n + 1, np.int64), np.zeros(0, np.int64)


#: (shift, mask) steps that spread 21 bits to every third bit of 63 (the "magic numbers" of Morton codes)
_SPREAD = ((32, 0x1F00000000FFFF), (16, 0x1F0000FF0000FF), (8, 0x100F00F00F00F00F), (4, 0x10C30C30C30C30C3),
           (2, 0x1249249249249249))  # fmt: skip


def _spread_bits(v: NDArray[np.uint64]) -> NDArray[np.uint64]:
    """Bit k of v moved to bit 3 k (v < 2^21)."""
    for shift, mask in _SPREAD:
        v = (v | (v << np.uint64(shift))) & np.uint64(mask)
    return v


def _morton_order(centres: NDArray[np.float64]) -> NDArray[np.int64]:
    """The permutation that sorts points along a Z-order curve (21 bits per axis)."""
    lo = centres.min(axis=0)
    extent = np.maximum(centres.max(axis=0) - lo, 1e-300)
    cells = np.minimum(((centres - lo) / extent * (1 << 21)).astype(np.int64), (1 << 21) - 1).astype(
        np.uint64
    )
    code = (
        _spread_bits(cells[:, 0])
        | (_spread_bits(cells[:, 1]) << np.uint64(1))
        | (_spread_bits(cells[:, 2]) << np.uint64(2))
    )
    return np.argsort(code, kind="stable")


def _visible_cells(tf, lo: NDArray, hi: NDArray) -> NDArray[np.bool_]:
    """Cells whose value range [lo, hi] reaches a non-zero opacity (NaN ranges: no)."""
    return visible_ranges(tf, lo, hi)
