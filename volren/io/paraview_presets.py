"""ParaView colour-map presets (.json) to our piecewise-linear transfer function.

A preset's colours interpolate in its ColorSpace (RGB, HSV, Lab, Diverging, ...) and its opacity
nodes carry a midpoint and a sharpness; neither is linear in general. Rather than reimplement
ParaView's interpolation, we build the same vtkColorTransferFunction / vtkPiecewiseFunction and
sample them: each interval is first tested at its quarter points, and only where it is not
already linear is it tabulated finely by VTK and simplified back to the fewest nodes that keep the
piecewise-linear curve within 2e-4 of VTK's.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from volren.errors import file_error
from volren.io import _pv
from volren.model.transfer_function import TransferFunction1D

TOLERANCE = 2e-4
_SAMPLES = 2049  # VTK samples per non-linear interval before simplification


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


def sample(
    table: _pv.Table, breaks: Sequence[float], tolerance: float = TOLERANCE, samples: int = _SAMPLES
) -> tuple[NDArray, NDArray]:
    """x (n,) and values (n, k) of a piecewise-linear curve within TOLERANCE of VTK's between `breaks`.

    An interval whose quarter points already lie on its chord is kept as one segment; any other
    is tabulated finely by VTK and simplified back to the samples that matter.
    """
    xs: list[NDArray] = []
    ys: list[NDArray] = []
    for x0, x1 in zip(breaks[:-1], breaks[1:]):
        if x1 <= x0:
            continue
        probe = table(x0, x1, 5)
        chord = probe[0] + np.linspace(0, 1, 5)[:, None] * (probe[-1] - probe[0])
        if np.max(np.abs(probe - chord)) <= tolerance:
            xs.append(np.array([x0, x1]))
            ys.append(probe[[0, -1]])
            continue
        x = np.linspace(x0, x1, samples)
        y = table(x0, x1, samples)
        keep = simplify_polyline(x, y, tolerance)
        xs.append(x[keep])
        ys.append(y[keep])
    if not xs:  # a single node
        x = np.array([float(breaks[0])])
        return x, table(x[0], x[0] + 1.0, 2)[:1]
    x, y = np.concatenate(xs), np.concatenate(ys)
    first = np.concatenate([[True], np.diff(x) > 0])  # intervals share their end points
    x, y = x[first], y[first]
    keep = simplify_polyline(x, y, 1e-12)  # drop nodes that sit on a straight line (e.g. linear midpoints)
    return x[keep], y[keep]


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
    log_scale = bool(preset.get("UseLogScale", False))
    if log_scale and rgb[0, 0] <= 0:
        raise file_error(path, f"preset {label}: UseLogScale needs positive RGBPoints x values")
    colors = _pv.color_table(rgb.tolist(), space, bool(preset.get("HSVWrap", False)), log_scale)
    if space.lower() in ("lab/ciede2000", "ciede2000"):
        # VTK quantizes this space's colours to 8 bits: match to that, not to a staircase
        cx, cy = sample(colors, rgb[:, 0].tolist(), tolerance=1.0 / 255, samples=513)
    else:
        cx, cy = sample(colors, rgb[:, 0].tolist())
    if "Points" in preset:
        nodes = _numbers(preset, "Points", 4, path, label)
        opacity = _pv.opacity_table(nodes.tolist())
        # midpoints are where the two halves of an interval meet: break there as well
        mids = nodes[:-1, 0] + nodes[:-1, 2] * np.diff(nodes[:, 0])
        ox, oy = sample(opacity, np.unique(np.concatenate([nodes[:, 0], mids])).tolist())
        opacity_points = np.column_stack([ox, np.clip(oy[:, 0], 0, 1)])
    else:
        # ParaView's default look for a colour map without opacity: a linear ramp over the colours.
        lo, hi = float(rgb[0, 0]), float(rgb[-1, 0])
        opacity_points = np.array([[lo, 0.0], [hi, 1.0]])
    color_points = np.column_stack([cx, np.clip(cy, 0, 1)])
    extra = {"name": preset["Name"]} if isinstance(preset.get("Name"), str) else {}
    return TransferFunction1D(color_points, opacity_points, extra=extra)
