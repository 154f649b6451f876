"""raycast's march in C (`march.c`), called as the numba kernels `march` and `march_pixels` (1D TFs
and label volumes) and `march2d` and `march2d_pixels` (2D TFs) are.

Why: the C build samples eight segments of a ray at a time with AVX2 gathers, which numba does not
emit here (`benchmarks.packet_probe`); where the library cannot be built or loaded
(`volren.kernels.native`: no compiler, ``VOLREN_NATIVE=0``) or a grid is too large for its 32-bit
gather offsets (a 2D TF's gradients: three int16 per value), `kernels` returns None and the numba kernels draw, the same image up to float
rounding.
"""

from __future__ import annotations

import ctypes
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from volren.kernels import native
from volren.renderers.raycast.march_inputs import (
    ChannelClassification,
    Classification,
    EmptyBricks,
    Gradients2D,
    LabelClassification,
    PixelView,
    Table2D,
)

SOURCE = Path(__file__).with_name("march.c")
#: Bytes readable past an 8-bit grid's last value: the vector path reads 32 bits at a value's offset.
SLACK = 4
#: The vector path's offsets into the grid are 32-bit.
MAX_VALUES = 2**31 - 1 - SLACK
#: With a 2D TF, into the gradients too: int16 offsets up to three per value, plus four.
MAX_VALUES_2D = (2**31 - 1 - 4) // 3
#: Bytes readable past a 2D table's interval kinds: the vector path reads four at a time.
KINDS_SLACK = 3

_i64 = ctypes.c_int64
_f64 = ctypes.c_double
_ptr = ctypes.c_void_p


class _Grid(ctypes.Structure):
    _fields_ = [("values", _ptr), ("nx", _i64), ("ny", _i64), ("nz", _i64), ("is_float", ctypes.c_int32)]


class _Bricks(ctypes.Structure):
    _fields_ = [("distance", _ptr), ("nbx", _i64), ("nby", _i64), ("nbz", _i64), ("size", _i64)]


class _View(ctypes.Structure):
    _fields_ = [("inverse", _ptr), ("width", _i64), ("height", _i64), ("grid_origin", _f64 * 3),
                ("spacing", _f64 * 3), ("view_dir", _f64 * 3), ("far_depth", _f64), ("phases", _ptr),
                ("planes", _ptr), ("n_planes", _i64)]  # fmt: skip


class _Classes(ctypes.Structure):
    _fields_ = [("preintegrated", ctypes.c_int32), ("cap", ctypes.c_int32), ("post", _ptr), ("post32", _ptr),
                ("n_post", _i64), ("table", _ptr), ("n_table", _i64), ("step", _f64), ("lo", _f64),
                ("scale", _f64), ("two_d", ctypes.c_int32), ("table2d", _ptr), ("n_value", _i64),
                ("n_gradient", _i64), ("g_scale", _f64), ("kinds", _ptr), ("gradients", _ptr),
                ("gradient_unit", _f64), ("labelled", ctypes.c_int32), ("labels_wide", ctypes.c_int32),
                ("labels", _ptr), ("lookup", _ptr), ("n_lookup", _i64), ("cells", _ptr), ("n_channels", _i64),
                ("channels", _ptr), ("channel_lo", _ptr), ("channel_scale", _ptr)]  # fmt: skip


def padded(values: NDArray[Any]) -> NDArray[Any]:
    """`values` C-contiguous, an 8-bit grid with `SLACK` readable bytes after its last value (the
    vector path reads four bytes at a time)."""
    if values.dtype != np.uint8:
        return np.ascontiguousarray(values)
    buffer = np.zeros(values.size + SLACK, np.uint8)
    buffer[: values.size] = values.reshape(-1)
    return buffer[: values.size].reshape(values.shape)


def _library() -> ctypes.CDLL | None:
    """The built library with its functions typed, or None."""
    lib = native.load(SOURCE)
    if lib is None:
        return None
    if not getattr(lib, "_volren_typed", False):
        common = [_ptr, _ptr, _ptr, _ptr, _f64, _ptr, _i64, _ptr, _ptr, ctypes.c_int]
        lib.march_tiles.argtypes = common
        lib.march_pixels.argtypes = [*common, _i64]
        lib.march_tiles.restype = lib.march_pixels.restype = ctypes.c_int
        lib.has_vector_path.restype = ctypes.c_int
        lib._volren_typed = True
    return lib


def _address(array: NDArray[Any]) -> int:
    return int(array.ctypes.data)


class _Frame:
    """The C structures of one call's arguments, holding the arrays they point into: a 1D TF's
    `Classification`, or a 2D TF's table and the grid's gradients."""

    def __init__(self, values: NDArray[Any], bricks: EmptyBricks, view: PixelView,
                 classes: Classification | LabelClassification | ChannelClassification | tuple[Gradients2D, Table2D]) -> None:  # fmt: skip
        nz, ny, nx = values.shape
        self.arrays = [
            np.ascontiguousarray(a, dtype=t)
            for a, t in (
                (bricks.distance, np.int8),
                (view.inverse, np.float64),
                (view.phases, np.float64),
                (view.planes, np.float64),
            )  # fmt: skip
        ]
        distance, inverse, phases, planes = self.arrays
        self.values = values
        self.grid = _Grid(_address(values), nx, ny, nz, 1 if values.dtype == np.float32 else 0)
        nbz, nby, nbx = distance.shape
        self.bricks = _Bricks(_address(distance), nbx, nby, nbz, int(bricks.size))
        self.view = _View(_address(inverse), int(view.width), int(view.height),
                          (_f64 * 3)(*map(float, view.grid_origin)), (_f64 * 3)(*map(float, view.spacing)),
                          (_f64 * 3)(*map(float, view.view_dir)), float(view.far_depth), _address(phases),
                          _address(planes), planes.shape[0])  # fmt: skip
        if isinstance(classes, LabelClassification):
            self.classes = self._classes_labels(classes)
        elif isinstance(classes, ChannelClassification):
            self.classes = self._classes_channels(classes)
        elif isinstance(classes, Classification):
            self.classes = self._classes_1d(classes)
        else:
            self.classes = self._classes_2d(*classes)

    def _kept(self, array: NDArray[Any], dtype: type) -> NDArray[Any]:
        kept = np.ascontiguousarray(array, dtype=dtype)
        self.arrays.append(kept)
        return kept

    def _classes_1d(self, classes: Classification) -> _Classes:
        post, post32 = self._kept(classes.post, np.float64), self._kept(classes.post, np.float32)
        table = self._kept(classes.table, np.float32)
        return _Classes(int(classes.preintegrated), int(classes.cap), _address(post), _address(post32),
                        post.shape[0], _address(table), table.shape[0], float(classes.step), float(classes.lo),
                        float(classes.scale))  # fmt: skip

    def _classes_labels(self, classes: LabelClassification) -> _Classes:
        post, post32 = self._kept(classes.post, np.float64), self._kept(classes.post, np.float32)
        labels, lookup, cells = classes.labels, self._kept(classes.lookup, np.int32), classes.cells
        if labels.shape != self.values.shape or labels.dtype not in (np.uint8, np.uint16) or post.ndim != 3:
            raise ValueError(
                "the C march reads 8- or 16-bit labels on the values' grid and (classes, n, 4) tables"
            )
        if cells.shape != self.values.shape or cells.dtype != np.int16 or not _has_slack(cells, 2):
            raise ValueError(
                "the C march reads int16 cell classes on the values' grid, 2 bytes readable past them"
            )
        labels = self._kept(labels, labels.dtype.type)
        none = self._kept(np.zeros(8), np.float64)
        return _Classes(0, 0, _address(post), _address(post32), post.shape[1], _address(none), 0, float(classes.step),
                        float(classes.lo), float(classes.scale), 0, _address(none), 0, 0, 0.0, _address(none),
                        _address(none), 0.0, 1, int(labels.dtype == np.uint16), _address(labels), _address(lookup),
                        lookup.shape[0], _address(cells))  # fmt: skip

    def _classes_channels(self, classes: ChannelClassification) -> _Classes:
        post, post32 = self._kept(classes.post, np.float64), self._kept(classes.post, np.float32)
        channels = classes.channels
        lo, scale = self._kept(classes.lo, np.float64), self._kept(classes.scale, np.float64)
        if channels.shape[1:] != self.values.shape or channels.dtype != self.values.dtype or post.ndim != 3:
            raise ValueError(
                "the C march reads channels on the values' grid, of their type, and (channels, n, 4) tables"
            )
        if len(channels) != len(post) or len(lo) != len(post) or len(scale) != len(post):
            raise ValueError("the C march reads a table, a lo and a scale per channel")
        if not channels.flags.c_contiguous or (channels.dtype == np.uint8 and not _has_slack(channels)):
            raise ValueError(
                f"the C march reads C-contiguous channels, 8-bit ones with {SLACK} bytes readable past them"
            )
        none = self._kept(np.zeros(8), np.float64)
        return _Classes(0, 0, _address(post), _address(post32), post.shape[1], _address(none), 0, float(classes.step),
                        0.0, 1.0, 0, _address(none), 0, 0, 0.0, _address(none), _address(none), 0.0, 0, 0,
                        _address(none), _address(none), 0, _address(none), len(channels), _address(channels),
                        _address(lo), _address(scale))  # fmt: skip

    def _classes_2d(self, grad: Gradients2D, tab: Table2D) -> _Classes:
        table = self._kept(tab.table, np.float32)
        kinds = self._kept(np.concatenate([tab.kinds, np.zeros(KINDS_SLACK, np.int8)]), np.int8)
        gradients = self._kept(grad.values, np.int16)
        if gradients.shape != (*self.values.shape, 3) or table.ndim != 3 or table.shape[2] != 4:
            raise ValueError("the C march reads (nz, ny, nx, 3) gradients and an (ng, nv, 4) table")
        if len(tab.kinds) != table.shape[1] - 1 or min(table.shape[:2]) < 2:
            raise ValueError("the C march reads a kind per interval of a table of at least 2 x 2 entries")
        none = self._kept(np.zeros(8), np.float64)
        return _Classes(0, 0, _address(none), _address(none), 2, _address(none), 0, float(tab.step), float(tab.lo),
                        float(tab.vscale), 1, _address(table), table.shape[1], table.shape[0], float(tab.gscale),
                        _address(kinds), _address(gradients), float(grad.unit))  # fmt: skip

    def pointers(self) -> list[Any]:
        return [ctypes.byref(self.grid), ctypes.byref(self.bricks), ctypes.byref(self.view),
                ctypes.byref(self.classes)]  # fmt: skip


def _checked(out: NDArray[Any], pixels: int, counts: NDArray[Any], rows: int) -> None:
    """The outputs as the C code writes them, large enough for what it writes (C checks no bound):
    float32 RGBA, `pixels` rows, and int64 counts (`march.COUNTS`), `rows` rows, C-contiguous."""
    if out.dtype != np.float32 or not out.flags.c_contiguous or out.size < 4 * pixels:
        raise ValueError(f"the C march writes {pixels} C-contiguous float32 RGBA pixels")
    if (
        counts.dtype != np.int64
        or not counts.flags.c_contiguous
        or counts.shape[1:] != (4,)
        or len(counts) < rows
    ):
        raise ValueError(f"the C march writes {rows} rows of C-contiguous int64 counts, four per row")


def _tiles(lib: ctypes.CDLL, frame: _Frame, term: float, tiles: NDArray[np.int64], out: NDArray[np.float32],
           counts: NDArray[np.int64]) -> None:  # fmt: skip
    tiles = np.ascontiguousarray(tiles, dtype=np.int64)
    if len(tiles) and tiles.min() < 0:
        raise ValueError("tile indices must not be negative")
    _checked(out, frame.view.width * frame.view.height, counts, int(tiles.max()) + 1 if len(tiles) else 0)
    lib.march_tiles(*frame.pointers(), float(term), _address(tiles), len(tiles), _address(out), _address(counts),
                    native.threads())  # fmt: skip


def _pixels(lib: ctypes.CDLL, frame: _Frame, term: float, pixels: NDArray[np.int64], out: NDArray[np.float32],
            counts: NDArray[np.int64], chunk: int) -> None:  # fmt: skip
    pixels = np.ascontiguousarray(pixels, dtype=np.int64)
    if len(pixels) and (pixels.min() < 0 or pixels.max() >= frame.view.width * frame.view.height):
        raise ValueError("pixel indices must lie in the image")
    _checked(out, len(pixels), counts, len(pixels))
    lib.march_pixels(*frame.pointers(), float(term), _address(pixels), len(pixels), _address(out), _address(counts),
                     native.threads(), int(chunk))  # fmt: skip


def _loaded() -> ctypes.CDLL:
    lib = _library()
    assert lib is not None
    return lib


def march(values: NDArray[Any], bricks: EmptyBricks, view: PixelView, classes: Classification, term: float,
          tiles: NDArray[np.int64], out: NDArray[np.float32], counts: NDArray[np.int64]) -> None:  # fmt: skip
    """As numba's `march.march`: the tiles into `out`, their counts (`march.COUNTS`) into `counts`."""
    _tiles(_loaded(), _Frame(values, bricks, view, classes), term, tiles, out, counts)


def march_pixels(values: NDArray[Any], bricks: EmptyBricks, view: PixelView, classes: Classification, term: float,
                 pixels: NDArray[np.int64], out: NDArray[np.float32], counts: NDArray[np.int64],
                 chunk: int = 16) -> None:  # fmt: skip
    """As numba's `march.march_pixels`: out[q] and counts[q] are pixels[q]'s."""
    _pixels(_loaded(), _Frame(values, bricks, view, classes), term, pixels, out, counts, chunk)


def march2d(values: NDArray[Any], grad: Gradients2D, bricks: EmptyBricks, view: PixelView, tab: Table2D,
            term: float, tiles: NDArray[np.int64], out: NDArray[np.float32],
            counts: NDArray[np.int64]) -> None:  # fmt: skip
    """As numba's `march2d.march2d`."""
    _tiles(_loaded(), _Frame(values, bricks, view, (grad, tab)), term, tiles, out, counts)


def march2d_pixels(values: NDArray[Any], grad: Gradients2D, bricks: EmptyBricks, view: PixelView, tab: Table2D,
                   term: float, pixels: NDArray[np.int64], out: NDArray[np.float32], counts: NDArray[np.int64],
                   chunk: int = 16) -> None:  # fmt: skip
    """As numba's `march2d.march2d_pixels`."""
    _pixels(_loaded(), _Frame(values, bricks, view, (grad, tab)), term, pixels, out, counts, chunk)


#: raycast's frames use numba's kernels meanwhile (`with numba_only(): ...`).
numba_only = native.NumbaOnly()


def kernels(values: NDArray[Any], kind: str = "1d") -> tuple[Any, Any] | None:
    """(march, march_pixels) in C for this grid (`kind` "1d", or "labels" and "channels": a
    `LabelClassification`'s or `ChannelClassification`'s march), or (march2d, march2d_pixels) for 2D
    TFs (`kind` "2d"), or None where
    the numba kernels must draw it: `numba_only` is on, ``VOLREN_NATIVE`` is 0 (read at each frame), the
    library is not available, the grid is too large for 32-bit offsets, its values are neither 8-bit nor
    float32, or an 8-bit grid lacks the slack `padded` gives."""
    if numba_only.on or not native.enabled():
        return None
    if (
        values.dtype not in (np.uint8, np.float32)
        or values.size > (MAX_VALUES_2D if kind == "2d" else MAX_VALUES)
        or not values.flags.c_contiguous
    ):
        return None
    if values.dtype == np.uint8 and not _has_slack(values):
        return None
    if _library() is None:
        return None
    return (march2d, march2d_pixels) if kind == "2d" else (march, march_pixels)


def _has_slack(values: NDArray[Any], slack: int = SLACK) -> bool:
    """Whether `slack` bytes past the array's last value lie inside the array that owns its memory."""
    owner = values.base
    if not isinstance(owner, np.ndarray):
        return False
    end = _address(values) + values.nbytes + slack
    return _address(owner) <= _address(values) and end <= _address(owner) + owner.nbytes


def vector_path() -> bool:
    """Whether the C march is available and built with the eight-sample vector path."""
    lib = _library()
    return lib is not None and bool(lib.has_vector_path())
