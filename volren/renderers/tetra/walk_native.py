"""tetra's cell walk in C (`walk.c`), called as numba's `traversal.cast_rays` is.

Why: the C walk reads each cell it steps through from one 192-byte record (`CellRecords`: planes,
gradient, neighbours and flags, three cache lines), where numba's reads six arrays, tests the four exit
faces at once, and finds each pixel's entry faces in its own threads (`FaceTiles`): 1.8-2.3x numba's
frames (`benchmarks.tetra_walk`). Where the library cannot be built or loaded (`volren.kernels.native`:
no compiler, ``VOLREN_NATIVE=0``) or a mesh has more cells than 32-bit neighbour ids hold, `available`
is False and numba's kernel draws, the same image up to float rounding.
"""

from __future__ import annotations

import ctypes
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from volren.kernels import native
from volren.kernels.ray_block import BinnedRays
from volren.kernels.shading import ShadeParams
from volren.kernels.tf_eval import PackedTF
from volren.renderers.tetra.entry_bins import EntryFaces
from volren.renderers.tetra.walk_inputs import SegmentTable, TetCells, WalkedSet, WalkOptions

SOURCE = Path(__file__).with_name("walk.c")
#: The C walk's `Cell` record.
CELL = np.dtype([("plane", "<f8", (4, 4)), ("gradient", "<f8", 3), ("neighbor", "<i4", 4), ("flags", "<u4"),
                 ("pad", "<u4", 5)])  # fmt: skip
USABLE, WALKABLE, VISIBLE = 1, 2, 4
#: Records start on a cache line, so that each spans exactly three.
ALIGN = 64

_i64 = ctypes.c_int64
_i32 = ctypes.c_int32
_f64 = ctypes.c_double
_ptr = ctypes.c_void_p


class _Mesh(ctypes.Structure):
    _fields_ = [("cells", _ptr), ("values", _ptr), ("corner", _ptr), ("boundary", _ptr), ("on_plane", _f64)]


class _Faces(ctypes.Structure):
    _fields_ = [("boxes", _ptr), ("edges", _ptr), ("cells", _ptr), ("tile_offsets", _ptr), ("tile_members", _ptr),
                ("width", _i64), ("tile", _i64), ("margin", _f64)]  # fmt: skip


class _Rays(ctypes.Structure):
    _fields_ = [("origins", _ptr), ("directions", _ptr), ("far", _ptr), ("pixels", _ptr), ("faces", _ptr),
                ("offsets", _ptr), ("candidates", _ptr), ("planes", _ptr), ("n_planes", _i64), ("cap", _i32)]  # fmt: skip


class FaceTiles(NamedTuple):
    """A frame's entry faces and their lists per `tile` x `tile` block of pixels (`entry_bins.bin_tiles`): the C walk
    finds each ray's faces itself, where numba's is handed them per pixel (`entry_bins.bin_triangles`)."""

    faces: EntryFaces
    offsets: NDArray[np.int64]
    members: NDArray[np.int64]
    tile: int


class _Table(ctypes.Structure):
    _fields_ = [("depth", _ptr), ("ratio", _ptr), ("n", _i64), ("layers", _i64), ("lo", _f64), ("scale", _f64),
                ("lmax", _f64)]  # fmt: skip


class _TF(ctypes.Structure):
    _fields_ = [("cx", _ptr), ("crgb", _ptr), ("ox", _ptr), ("oa", _ptr), ("nc", _i64), ("no", _i64)]


class _Shade(ctypes.Structure):
    _fields_ = [("on", _i32), ("ambient", _f64), ("diffuse", _f64), ("specular", _f64), ("power", _f64),
                ("gradient_threshold", _f64), ("lx", _f64), ("ly", _f64), ("lz", _f64)]  # fmt: skip


class _Options(ctypes.Structure):
    _fields_ = [("mode", _i32), ("termination", _f64), ("max_steps", _i64)]


def _library() -> ctypes.CDLL | None:
    """The built library with its functions typed and its record layout checked, or None."""
    lib = native.load(SOURCE)
    if lib is None:
        return None
    if not getattr(lib, "_volren_typed", False):
        lib.cast_rays.argtypes = [_ptr] * 6 + [_i64, _ptr, _ptr, _ptr, ctypes.c_int]
        lib.cast_rays.restype = ctypes.c_int
        lib.packed_planes.argtypes = [_ptr, _ptr, _i64, _ptr, ctypes.c_int]
        lib.packed_planes.restype = ctypes.c_int
        lib.fill_cells.argtypes = [_ptr, _ptr, _ptr, _ptr, _i64, _ptr, ctypes.c_int]
        lib.fill_cells.restype = ctypes.c_int
        lib.cell_bytes.restype = _i64
        if lib.cell_bytes() != CELL.itemsize:
            return None
        lib._volren_typed = True
    return lib


#: tetra's CPU walks use numba's kernels meanwhile (`with numba_only(): ...`).
numba_only = native.NumbaOnly()


def available(cells: int) -> bool:
    """Whether the C walk draws a mesh of `cells` cells: `numba_only` is off, ``VOLREN_NATIVE`` is not 0
    (read at each call), the library builds and loads, and the cell ids fit 32 bits."""
    return not numba_only.on and native.enabled() and cells < 2**31 - 1 and _library() is not None


def _address(array: NDArray[Any]) -> int:
    return int(array.ctypes.data)


def _aligned(n: int) -> NDArray[np.void]:
    """Room for n `CELL` records starting on an `ALIGN`-byte boundary."""
    raw = np.empty(n * CELL.itemsize + ALIGN, np.uint8)
    start = (-_address(raw)) % ALIGN
    return raw[start : start + n * CELL.itemsize].view(CELL)


class CellRecords:
    """The walk's `Cell` records of one mesh (`TetCells`): the geometry once, the flags again for each
    walked set (`WalkedSet`), which a TF edit changes."""

    def __init__(self, cells: TetCells) -> None:
        m = len(cells.neighbors)
        arrays = [np.ascontiguousarray(a, dtype=t) for a, t in ((cells.planes, np.float64), (cells.gradients, np.float64),
                  (cells.neighbors, np.int64), (cells.usable, np.uint8))]  # fmt: skip
        planes, gradients, neighbors, usable = arrays
        if (
            planes.shape != (m, 4, 4)
            or gradients.shape != (m, 3)
            or neighbors.shape != (m, 4)
            or usable.shape != (m,)
        ):
            raise ValueError(
                "the C walk reads (m, 4, 4) planes, (m, 3) gradients, (m, 4) neighbours and (m,) flags"
            )
        if m and (neighbors.min() < -1 or neighbors.max() >= m):
            raise ValueError("neighbours must be cell ids or -1")
        self.records = _aligned(m)
        lib = _library()
        assert lib is not None
        lib.fill_cells(*(_address(a) for a in arrays), m, _address(self.records), native.threads())
        self._usable = np.where(usable, np.uint32(USABLE), np.uint32(0))
        self._flags_of: tuple[Any, Any] | None = None

    def flags(self, walked: WalkedSet) -> None:
        """Set the flags of `walked` (kept while the same arrays are passed)."""
        key = (walked.walkable, walked.visible)
        if self._flags_of is not None and all(a is b for a, b in zip(key, self._flags_of, strict=True)):
            return
        flags = self._usable.copy()
        flags[walked.walkable] |= np.uint32(WALKABLE)
        flags[walked.visible] |= np.uint32(VISIBLE)
        self.records["flags"] = flags
        self._flags_of = key


def _bytes(flags: NDArray[np.bool_], kept: list[NDArray[Any]]) -> int:
    """The address of boolean flags as bytes: a view where they are contiguous (a copy of oxygen's (m, 4) faces took
    2 ms, once per block of rows)."""
    flags = np.ascontiguousarray(flags, dtype=np.bool_)
    kept.append(flags)
    return _address(flags.view(np.uint8))


def cast_rays(records: CellRecords, rays: BinnedRays, cells: TetCells, walked: WalkedSet, table: SegmentTable,
              tf: PackedTF, options: WalkOptions, sp: ShadeParams, out: NDArray[np.float64],
              stats: NDArray[np.int64] | None, totals: NDArray[np.int64], tiles: FaceTiles | None = None,
              pixels: NDArray[np.int64] | None = None) -> None:  # fmt: skip
    """As numba's `traversal.cast_rays`, with `records` built from `cells`, composites clipped to valid premultiplied
    colours as `TetraRenderer._pixels` clips numba's; the per-ray `stats` kept only where given, their sums and the
    rays that took a step added to `totals` (5,). With `tiles`, ray q's candidates are first the cells of the faces
    covering its pixel `pixels[q]`, then its listed ones (`rays.offsets`)."""
    lib = _library()
    assert lib is not None
    n = len(rays.origins)
    if out.dtype != np.float64 or not out.flags.c_contiguous or out.shape != (n, 4):
        raise ValueError(f"the C walk writes ({n}, 4) C-contiguous float64 pixels")
    if stats is not None and (
        stats.dtype != np.int64 or not stats.flags.c_contiguous or stats.shape != (n, 4)
    ):
        raise ValueError(f"the C walk writes ({n}, 4) C-contiguous int64 counters")
    if totals.dtype != np.int64 or not totals.flags.c_contiguous or totals.shape != (5,):
        raise ValueError("the C walk adds to 5 C-contiguous int64 totals")
    records.flags(walked)
    kept: list[NDArray[Any]] = []

    def arr(a: Any, dtype: Any) -> int:
        kept.append(np.ascontiguousarray(a, dtype=dtype))
        return _address(kept[-1])

    planes = np.ascontiguousarray(rays.planes, dtype=np.float64).reshape(-1, 4)
    kept.append(planes)
    mesh = _Mesh(_address(records.records), arr(cells.values, np.float64), arr(cells.corner, np.float64),
                 _bytes(walked.boundary, kept), float(cells.on_plane))  # fmt: skip
    faces = None
    if tiles is not None:
        face = tiles.faces
        if pixels is None or len(pixels) != n:
            raise ValueError(f"the C walk reads a pixel for each of the {n} rays")
        if len(pixels) and (pixels.min() < 0 or pixels.max() >= face.width * face.height):
            raise ValueError("pixel indices must lie in the image")
        if len(tiles.offsets) != -(-face.width // tiles.tile) * -(-face.height // tiles.tile) + 1:
            raise ValueError("the C walk reads a face list per tile of the image")
        faces = _Faces(arr(face.boxes, np.int64), arr(face.edges, np.float64), arr(face.cells, np.int64),
                       arr(tiles.offsets, np.int64), arr(tiles.members, np.int64), int(face.width), int(tiles.tile),
                       float(face.margin))  # fmt: skip
    ray = _Rays(arr(rays.origins, np.float64), arr(rays.directions, np.float64), arr(rays.far, np.float64),
                0 if faces is None else arr(pixels, np.int64), 0 if faces is None else ctypes.addressof(faces),
                arr(rays.offsets, np.int64), arr(rays.candidates, np.int64), _address(planes), len(planes),
                int(bool(rays.cap)))  # fmt: skip
    depth = np.ascontiguousarray(table.depth_per_length[..., 0], dtype=np.float64)
    ratio = _entry_major(table.colour_ratio)
    if depth.shape != ratio.shape[:2]:
        raise ValueError("the C walk reads an (n, n, 1) optical depth table beside the colour ratios")
    kept += [depth, ratio]
    tab = _Table(_address(depth), _address(ratio), depth.shape[0], ratio.shape[2], float(table.lo),
                 float(table.scale), float(table.lmax))  # fmt: skip
    packed = _TF(arr(tf.color_x, np.float64), arr(tf.color_rgb, np.float64), arr(tf.opacity_x, np.float64),
                 arr(tf.opacity_a, np.float64), len(tf.color_x), len(tf.opacity_x))  # fmt: skip
    shade = _Shade(int(bool(sp.on)), float(sp.ambient), float(sp.diffuse), float(sp.specular), float(sp.power),
                   float(sp.gradient_threshold), float(sp.lx), float(sp.ly), float(sp.lz))  # fmt: skip
    opts = _Options(int(options.mode), float(options.termination), int(options.max_steps))
    lib.cast_rays(ctypes.byref(ray), ctypes.byref(mesh), ctypes.byref(tab), ctypes.byref(packed), ctypes.byref(shade),
                  ctypes.byref(opts), n, _address(out), 0 if stats is None else _address(stats), _address(totals),
                  native.threads())  # fmt: skip


#: (the last table, its colour ratios laid out by entry): a frame walks its rows in several calls
_entry_major_of: list[tuple[NDArray[Any], NDArray[np.float64]]] = []


def _entry_major(ratio: NDArray[Any]) -> NDArray[np.float64]:
    """The (K, n, n, 3) colour ratios as (n, n, K, 3), where the C walk reads both length layers of an
    entry as six doubles in a row; one layer is given twice (the walk interpolates between two)."""
    if _entry_major_of and _entry_major_of[0][0] is ratio:
        return _entry_major_of[0][1]
    if ratio.ndim != 4 or ratio.shape[3] != 3 or ratio.shape[1] != ratio.shape[2] or ratio.shape[1] < 2:
        raise ValueError("the C walk reads (K, n, n, 3) colour ratios with n >= 2")
    layers = ratio if ratio.shape[0] > 1 else np.concatenate([ratio, ratio])
    laid = np.ascontiguousarray(np.transpose(layers, (1, 2, 0, 3)), dtype=np.float64)
    _entry_major_of[:] = [(ratio, laid)]
    return laid


def packed_planes(points: NDArray[np.float64], tets: NDArray[np.int64]) -> NDArray[np.float64] | None:
    """`tet_planes.packed_face_planes` in C, or None where the library is not available."""
    if numba_only.on or not native.enabled():
        return None
    lib = _library()
    if lib is None:
        return None
    points = np.ascontiguousarray(points, dtype=np.float64)
    tets = np.ascontiguousarray(tets, dtype=np.int64)
    if len(tets) and (tets.min() < 0 or tets.max() >= len(points)):
        raise ValueError("cell corners must index the points")
    out = np.empty((len(tets), 4, 4))
    lib.packed_planes(_address(points), _address(tets), len(tets), _address(out), native.threads())
    return out
