"""ParaView colour-map presets (.json) to our piecewise-linear transfer function.

A preset's colours interpolate in its ColorSpace (RGB, HSV, Lab, Diverging, ...) and its opacity
nodes carry a midpoint and a sharpness; neither is linear in general. Rather than reimplement
ParaView's interpolation, we build the same vtkColorTransferFunction / vtkPiecewiseFunction and
sample them: each interval is first tested at its quarter points, and only where it is not
already linear is it tabulated finely by VTK and simplified back to the fewest nodes that keep the
piecewise-linear curve within 2e-4 of VTK's.

The work is linear in the preset's points: VTK sorts all nodes of a function on each insertion
and scans them from the first on each evaluation, so one function through 20,000 nodes took
minutes; the curve is evaluated by functions of a few nodes each instead (`chunked_table`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError, file_error
from volren.io import _pv
from volren.model.transfer_function import MAX_POINTS, TransferFunction1D

TOLERANCE = 2e-4
_SAMPLES = 2049  # VTK samples per non-linear interval before simplification
#: Intervals per VTK function in `chunked_table`: small enough that VTK's per-node costs stay
#: small, large enough that building the functions costs little.
_CHUNK = 64
#: Nodes per block when a long stretch of nodes is simplified (`_simplify_stretch`).
_BLOCK = 1024
#: Most RGBPoints read in the Lab/CIEDE2000 colour space: VTK works out each segment's colour
#: path anew on every evaluation (about 0.1 s), so a preset of thousands of points would take
#: many minutes; ParaView's own presets in that space have a handful.
MAX_CIEDE2000_POINTS = 64
_CIEDE2000 = ("lab/ciede2000", "ciede2000")


def is_preset_data(data: Any) -> bool:
    """A list of preset objects, or one object with ParaView's keys."""
    if isinstance(data, list):
        return bool(data) and all(isinstance(p, Mapping) for p in data)
    return isinstance(data, Mapping) and any(k in data for k in ("RGBPoints", "IndexedColors", "ColorSpace"))


def select_preset(data: Any, name: str | None, path: Path) -> Mapping[str, Any]:
    presets = data if isinstance(data, list) else [data]
    if name is None:
        return presets[0]
    for preset in presets:
        if preset.get("Name") == name:
            return preset
    names = [str(p.get("Name")) for p in presets]
    shown = ", ".join(repr(n) for n in names[:30]) + (
        f", ... ({len(names) - 30} more)" if len(names) > 30 else ""
    )
    raise file_error(path, f"no preset named {name!r}; available: {shown}")


def _numbers(preset: Mapping[str, Any], key: str, width: int, path: Path, label: str) -> NDArray:
    raw = preset[key]
    if not isinstance(raw, list) or not all(
        isinstance(v, int | float) and not isinstance(v, bool) for v in raw
    ):
        raise file_error(path, f"preset {label}: '{key}' must be a list of numbers")
    if len(raw) == 0 or len(raw) % width:
        raise file_error(
            path, f"preset {label}: '{key}' must hold groups of {width} numbers, got {len(raw)} numbers"
        )
    if len(raw) // width > MAX_POINTS:
        raise file_error(
            path, f"preset {label}: '{key}' has {len(raw) // width:,} points; a transfer function has at "
            f"most {MAX_POINTS:,}"
        )  # fmt: skip
    arr = np.asarray(raw, dtype=np.float64).reshape(-1, width)
    if not np.all(np.isfinite(arr)):
        raise file_error(path, f"preset {label}: '{key}' contains NaN or Inf")
    if np.any(np.diff(arr[:, 0]) < 0):
        raise file_error(path, f"preset {label}: the x values of '{key}' must not decrease")
    if np.any(arr[:, 1:] < 0) or np.any(arr[:, 1:] > 1):
        raise file_error(path, f"preset {label}: the values in '{key}' after each x must lie in [0, 1]")
    return arr


def simplify_polyline(x: NDArray, y: NDArray, tolerance: float) -> NDArray[np.int64]:
    """Indices of the samples that keep linear interpolation within `tolerance` (Douglas-Peucker)."""
    keep = np.zeros(len(x), dtype=bool)
    keep[[0, -1]] = True
    stack = [(0, len(x) - 1)]
    while stack:
        i, j = stack.pop()
        if j - i < 2:
            continue
        t = (x[i + 1 : j] - x[i]) / (x[j] - x[i])
        chord = y[i] + t[:, None] * (y[j] - y[i])
        err = np.max(np.abs(y[i + 1 : j] - chord), axis=1)
        k = int(np.argmax(err))
        if err[k] > tolerance:
            m = i + 1 + k
            keep[m] = True
            stack += [(i, m), (m, j)]
    return np.flatnonzero(keep)


def last_of_equal_x(nodes: NDArray) -> NDArray:
    """The nodes without those whose x the next node repeats: VTK replaces a node added at the x
    of an earlier one, so the last of equal x is the one it uses."""
    return nodes[np.append(np.diff(nodes[:, 0]) > 0, True)]


def chunked_table(build: Callable[[list], _pv.Table], nodes: NDArray, chunk: int = _CHUNK) -> _pv.Table:
    """VTK's curve through `nodes` (x sorted and distinct), `build` making a VTK function of a
    list of nodes, for tables that each lie within one interval between nodes. Between two nodes
    VTK's curve depends on them and their neighbours only, so a function of the chunk of nodes
    around an interval gives the same values as one of all nodes, at a cost that does not grow
    with their number."""
    xs = nodes[:, 0]
    built: dict[int, _pv.Table] = {}

    def table(x0: float, x1: float, n: int) -> NDArray:
        interval = max(int(np.searchsorted(xs, x0, side="right")) - 1, 0)
        first = interval // chunk * chunk
        if first not in built:
            built[first] = build(nodes[max(first - 1, 0) : first + chunk + 2].tolist())
        return built[first](x0, x1, n)

    return table


def _too_many(tolerance: float) -> VolrenError:
    return VolrenError(
        f"needs more than {MAX_POINTS:,} points to follow VTK's curve within {tolerance:g}, the most a "
        "transfer function has"
    )


def sample(
    table: _pv.Table, breaks: Sequence[float], tolerance: float = TOLERANCE, samples: int = _SAMPLES
) -> tuple[NDArray, NDArray]:
    """x (n,) and values (n, k) of a piecewise-linear curve within TOLERANCE of VTK's between `breaks`.

    An interval whose quarter points already lie on its chord is kept as one segment; any other
    is tabulated finely by VTK and simplified back to the samples that matter. Each interval
    starts where the one before it ended; more than MAX_POINTS points is a VolrenError, raised
    before the fine tabulation when the intervals that need it are already too many.
    """
    ends = np.unique(np.asarray(breaks, dtype=np.float64))
    if len(ends) == 1:  # a single node
        return ends, table(ends[0], ends[0] + 1.0, 2)[:1]
    probes = np.stack([table(x0, x1, 5) for x0, x1 in zip(ends[:-1], ends[1:])])  # (intervals, 5, k)
    chord = probes[:, :1] + np.linspace(0, 1, 5)[None, :, None] * (probes[:, -1:] - probes[:, :1])
    curved = np.flatnonzero(np.abs(probes - chord).max(axis=(1, 2)) > tolerance)
    if len(ends) + len(curved) > MAX_POINTS:  # each curved interval keeps a sample inside it
        raise _too_many(tolerance)
    fine: dict[int, tuple[NDArray, NDArray]] = {}  # a curved interval's samples after its start
    count = len(ends)
    for i in curved:
        x = np.linspace(ends[i], ends[i + 1], samples)
        y = table(ends[i], ends[i + 1], samples)
        keep = simplify_polyline(x, y, tolerance)[1:]
        fine[i] = x[keep], y[keep]
        count += len(keep) - 1
        if count > MAX_POINTS:
            raise _too_many(tolerance)
    xs, ys = [ends[:1]], [probes[0, :1]]
    for i in range(len(ends) - 1):
        x, y = fine.get(i, (ends[i + 1 : i + 2], probes[i, -1:]))
        xs.append(x)
        ys.append(y)
    x, y = np.concatenate(xs), np.concatenate(ys)
    keep = _drop_collinear(x, y)  # e.g. linear midpoints
    return x[keep], y[keep]


def _drop_collinear(x: NDArray, y: NDArray, tolerance: float = 1e-12) -> NDArray[np.int64]:
    """Indices of the nodes left after dropping those on a straight line (within `tolerance`)
    between their neighbours: linear midpoints, a preset's straight stretches. A node off the
    line through its two neighbours stays; `simplify_polyline` decides only within each stretch
    between two such nodes, so its cost follows the stretches, not all nodes."""
    if len(x) < 3:
        return np.arange(len(x))
    t = (x[1:-1] - x[:-2]) / (x[2:] - x[:-2])
    off_line = np.abs(y[1:-1] - (y[:-2] + t[:, None] * (y[2:] - y[:-2]))).max(axis=1) > tolerance
    corners = np.flatnonzero(np.concatenate([[True], off_line, [True]]))
    kept = [corners]
    for a, b in zip(corners[:-1], corners[1:]):
        if b - a > 1:
            kept.append(a + _simplify_stretch(x[a : b + 1], y[a : b + 1], tolerance))
    return np.unique(np.concatenate(kept))


def _simplify_stretch(x: NDArray, y: NDArray, tolerance: float) -> NDArray[np.int64]:
    """`simplify_polyline` on a stretch of nodes each on the line through its neighbours: at once
    when it is straight as a whole, else a block at a time (on a curve bending steadily one way
    it splits off one node per step, quadratic in the nodes it is given at once)."""
    chord = y[0] + ((x - x[0]) / (x[-1] - x[0]))[:, None] * (y[-1] - y[0])
    if np.abs(y - chord).max() <= tolerance:
        return np.array([0, len(x) - 1])
    starts = range(0, len(x) - 1, _BLOCK)
    return np.unique(np.concatenate(
        [start + simplify_polyline(x[start : start + _BLOCK + 1], y[start : start + _BLOCK + 1], tolerance)
         for start in starts]
    ))  # fmt: skip


def preset_to_tf(preset: Mapping[str, Any], path: Path) -> TransferFunction1D:
    """Our TF for one preset object; colours and opacities match VTK's to TOLERANCE."""
    label = repr(preset.get("Name", "(unnamed)"))
    if "RGBPoints" not in preset:
        problem = (
            "is an indexed (categorical) colour map" if "IndexedColors" in preset else "has no 'RGBPoints'"
        )
        raise file_error(path, f"preset {label} {problem}; a transfer function needs RGBPoints")
    rgb = _numbers(preset, "RGBPoints", 4, path, label)
    space = str(preset.get("ColorSpace", "RGB"))
    if space.lower() not in _pv.COLOR_SPACES:
        raise file_error(
            path, f"preset {label}: unknown ColorSpace {space!r}; known: {', '.join(_pv.COLOR_SPACES)}"
        )
    if space.lower() in _CIEDE2000 and len(rgb) > MAX_CIEDE2000_POINTS:
        raise file_error(
            path, f"preset {label}: {len(rgb):,} RGBPoints in the {space} colour space, where VTK takes "
            f"about 0.1 s per segment; volren reads at most {MAX_CIEDE2000_POINTS} there"
        )  # fmt: skip
    log_scale = bool(preset.get("UseLogScale", False))
    if log_scale and rgb[0, 0] <= 0:
        raise file_error(path, f"preset {label}: UseLogScale needs positive RGBPoints x values")
    rgb = last_of_equal_x(rgb)
    wrap = bool(preset.get("HSVWrap", False))
    colors = chunked_table(lambda nodes: _pv.color_table(nodes, space, wrap, log_scale), rgb)
    try:
        if space.lower() in _CIEDE2000:
            # VTK quantizes this space's colours to 8 bits: match to that, not to a staircase
            cx, cy = sample(colors, rgb[:, 0], tolerance=1.0 / 255, samples=513)
        else:
            cx, cy = sample(colors, rgb[:, 0])
    except VolrenError as exc:
        raise file_error(path, f"preset {label}: its colour map {exc}") from None
    if "Points" in preset:
        nodes = last_of_equal_x(_numbers(preset, "Points", 4, path, label))
        opacity = chunked_table(_pv.opacity_table, nodes)
        # midpoints are where the two halves of an interval meet: break there as well
        mids = nodes[:-1, 0] + nodes[:-1, 2] * np.diff(nodes[:, 0])
        try:
            ox, oy = sample(opacity, np.concatenate([nodes[:, 0], mids]))
        except VolrenError as exc:
            raise file_error(path, f"preset {label}: its opacity {exc}") from None
        opacity_points = np.column_stack([ox, np.clip(oy[:, 0], 0, 1)])
    else:
        # ParaView's default look for a colour map without opacity: a linear ramp over the colours.
        lo, hi = float(rgb[0, 0]), float(rgb[-1, 0])
        opacity_points = np.array([[lo, 0.0], [hi, 1.0]])
    color_points = np.column_stack([cx, np.clip(cy, 0, 1)])
    extra = {"name": preset["Name"]} if isinstance(preset.get("Name"), str) else {}
    return TransferFunction1D(color_points, opacity_points, extra=extra)
