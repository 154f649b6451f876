"""The 1D transfer function: colour and opacity, piecewise linear in the data value.

Optical model (DESIGN.md): the opacity a(s) is that of a slab `opacity_unit_distance` thick, so
the extinction is tau(s) = -ln(1 - min(a, 1 - 1e-6)) / d_u and the emission q(s) = c(s) tau(s).
Both colour and opacity are constant beyond their first and last control points.

Every edit bumps `version`, drawn from one process-wide counter, so that a (version, ...) key
identifies the TF contents uniquely across instances: caches of tables and textures key on it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from volren.errors import VolrenError
from volren.model.file_version import check_format_version
from volren.model.versioned import Versioned

#: Opacities are clamped to this before taking the logarithm (DESIGN.md).
MAX_OPACITY = 1.0 - 1e-6
#: Shorter unit distances would make the extinction of opaque values (13.8 / d_u) overflow in
#: tables and integrators; no physical length is this small.
MIN_UNIT_DISTANCE = 1e-30
TF_FORMAT_VERSION = 1
#: Most colour or opacity control points a TF may have: far above any TF drawn by hand or read
#: from a preset (ParaView's have hundreds), and where every renderer still takes it in under a
#: second; above it a TF is refused rather than made slow.
MAX_POINTS = 100_000


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float | np.integer | np.floating) and not isinstance(value, bool)


def _check_numbers(data: ArrayLike, what: str) -> None:
    """Refuse anything but numbers (or lists of them): np.array(..., float) would turn the
    strings ("0.5") and booleans of a hand-written file into numbers without a word."""
    if isinstance(data, np.ndarray) and data.dtype.kind in "iuf":
        return
    rows = data if isinstance(data, list | tuple | np.ndarray) else [data]
    for row in rows:
        for value in row if isinstance(row, list | tuple | np.ndarray) else [row]:
            if not _is_number(value):
                raise VolrenError(f"{what} points must be numbers, got {value!r}")


def _points(data: ArrayLike, width: int, what: str) -> NDArray[np.float64]:
    _check_numbers(data, what)
    try:
        arr = np.array(data, dtype=np.float64)
    except ValueError:  # rows of different lengths
        raise VolrenError(f"{what} points must be a non-empty list of {width}-tuples") from None
    except OverflowError:  # an integer beyond float64's range
        raise VolrenError(f"{what} points hold a number beyond float64's range (1.8e308)") from None
    if arr.ndim == 1 and arr.size % width == 0 and arr.size:
        arr = arr.reshape(-1, width)
    if arr.ndim != 2 or arr.shape[1] != width or len(arr) == 0:
        raise VolrenError(f"{what} points must be a non-empty list of {width}-tuples, got shape {arr.shape}")
    if len(arr) > MAX_POINTS:
        raise VolrenError(f"{what} has {len(arr)} points; a transfer function has at most {MAX_POINTS}")
    if not np.all(np.isfinite(arr)):
        raise VolrenError(f"{what} points contain NaN or Inf")
    if np.any(arr[:, 1:] < 0) or np.any(arr[:, 1:] > 1):
        raise VolrenError(f"{what} values must lie in [0, 1]")
    order = np.argsort(arr[:, 0], kind="stable")
    return arr[order]


class TransferFunction1D(Versioned):
    """Colour and opacity control points over the data value, with change notification."""

    #: The TF's dimension: renderers check it against their capabilities (`KindSupport.tf_dims`).
    dims: ClassVar[int] = 1

    def __init__(
        self,
        color: ArrayLike,
        opacity: ArrayLike,
        opacity_unit_distance: float = 1.0,
        extra: Mapping[str, Any] | None = None,
    ) -> None:
        self._color = _points(color, 4, "colour")
        self._opacity = _points(opacity, 2, "opacity")
        self._unit = self._check_unit(opacity_unit_distance)
        self.extra: dict[str, Any] = dict(extra or {})
        super().__init__()

    # ----------------------------------------------------------------- construction helpers
    @classmethod
    def ramp(
        cls,
        lo: float,
        hi: float,
        max_opacity: float = 1.0,
        color: ArrayLike = (1.0, 1.0, 1.0),
        opacity_unit_distance: float = 1.0,
    ) -> TransferFunction1D:
        """A linear opacity ramp from 0 at `lo` to `max_opacity` at `hi`, in one colour."""
        r, g, b = np.asarray(color, dtype=float)
        return cls([[lo, r, g, b], [hi, r, g, b]], [[lo, 0.0], [hi, max_opacity]], opacity_unit_distance)

    @classmethod
    def constant(
        cls, opacity: float, color: ArrayLike = (1.0, 1.0, 1.0), opacity_unit_distance: float = 1.0
    ) -> TransferFunction1D:
        """The same colour and opacity for every value."""
        r, g, b = np.asarray(color, dtype=float)
        return cls([[0.0, r, g, b]], [[0.0, opacity]], opacity_unit_distance)

    @staticmethod
    def _check_unit(value: float) -> float:
        if isinstance(value, bool):
            raise VolrenError(f"opacity_unit_distance must be a number, got {value!r}")
        try:
            unit = float(value)
        except (TypeError, ValueError, OverflowError):
            raise VolrenError(f"opacity_unit_distance must be a number, got {value!r}") from None
        if not math.isfinite(unit) or unit <= 0:
            raise VolrenError(f"opacity_unit_distance must be positive and finite, got {value!r}")
        if unit < MIN_UNIT_DISTANCE:
            raise VolrenError(
                f"opacity_unit_distance {value!r} is absurdly small (at least {MIN_UNIT_DISTANCE:g})"
            )
        return unit

    # ------------------------------------------------------------------------------ state
    @property
    def color_points(self) -> NDArray[np.float64]:
        """(n, 4) array of [x, r, g, b], sorted by x (a copy)."""
        return self._color.copy()

    @property
    def opacity_points(self) -> NDArray[np.float64]:
        """(m, 2) array of [x, a], sorted by x (a copy)."""
        return self._opacity.copy()

    @property
    def opacity_unit_distance(self) -> float:
        return self._unit

    @property
    def value_range(self) -> tuple[float, float]:
        """The span of all control points: where the TF is not constant."""
        xs = np.concatenate([self._color[:, 0], self._opacity[:, 0]])
        return (float(xs.min()), float(xs.max()))

    def breakpoints(self) -> NDArray[np.float64]:
        """Sorted distinct x of all control points: between two of them everything is linear."""
        return np.unique(np.concatenate([self._color[:, 0], self._opacity[:, 0]]))

    def linear_cuts(self) -> NDArray[np.float64]:
        """`breakpoints` plus the values where the opacity crosses the clamp 1 - 1e-6: between two
        cuts colour, opacity and the clamped opacity (hence the extinction's form) are smooth."""
        ox, oa = self._opacity[:, 0], self._opacity[:, 1]
        crossings = [
            ox[k] + (MAX_OPACITY - oa[k]) / (oa[k + 1] - oa[k]) * (ox[k + 1] - ox[k])
            for k in range(len(ox) - 1)
            if ox[k + 1] > ox[k] and min(oa[k], oa[k + 1]) < MAX_OPACITY < max(oa[k], oa[k + 1])
        ]
        return np.unique(np.concatenate([self.breakpoints(), np.asarray(crossings, dtype=np.float64)]))

    # ------------------------------------------------------------------------------ edits
    def set_color_points(self, points: ArrayLike) -> None:
        self._color = _points(points, 4, "colour")
        self._changed()

    def set_opacity_points(self, points: ArrayLike) -> None:
        self._opacity = _points(points, 2, "opacity")
        self._changed()

    def set_opacity_unit_distance(self, value: float) -> None:
        self._unit = self._check_unit(value)
        self._changed()

    def rescale(self, lo: float, hi: float) -> None:
        """Map the control points linearly from the current value range onto [lo, hi]."""
        old_lo, old_hi = self.value_range
        if not (math.isfinite(lo) and math.isfinite(hi)) or hi < lo:
            raise VolrenError(f"cannot rescale a transfer function to [{lo}, {hi}]")
        scale = 0.0 if old_hi == old_lo else (hi - lo) / (old_hi - old_lo)
        self._color[:, 0] = lo + (self._color[:, 0] - old_lo) * scale
        self._opacity[:, 0] = lo + (self._opacity[:, 0] - old_lo) * scale
        self._changed()

    def copy(self) -> TransferFunction1D:
        return TransferFunction1D(self._color, self._opacity, self._unit, self.extra)

    # ---------------------------------------------------------------------------- sampling
    def sample(self, values: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Colour (..., 3) and opacity (...) at `values`; NaN values get opacity 0, colour 0."""
        v = np.asarray(values, dtype=np.float64)
        bad = ~np.isfinite(v)
        flat = np.where(bad, 0.0, v).reshape(-1)
        rgb = np.stack([np.interp(flat, self._color[:, 0], self._color[:, c]) for c in (1, 2, 3)], axis=-1)
        alpha: NDArray[np.float64] = np.interp(flat, self._opacity[:, 0], self._opacity[:, 1])
        # np.interp may round a hair outside [0, 1] between nearly coincident points.
        rgb = np.clip(rgb, 0.0, 1.0).reshape(v.shape + (3,))
        alpha = np.clip(alpha, 0.0, 1.0).reshape(v.shape)
        if bad.any():
            rgb[bad] = 0.0
            alpha[bad] = 0.0
        return rgb, alpha

    def extinction(self, values: ArrayLike) -> NDArray[np.float64]:
        """tau(s) = -ln(1 - min(a(s), 1 - 1e-6)) / opacity_unit_distance, per unit length."""
        _, alpha = self.sample(values)
        return -np.log1p(-np.minimum(alpha, MAX_OPACITY)) / self._unit

    def to_lut(self, n: int = 256, value_range: tuple[float, float] | None = None) -> NDArray[np.float32]:
        """(n, 4) float32 [r, g, b, a] (colour not premultiplied) at lo + (hi - lo) k / (n - 1)."""
        if n < 2:
            raise VolrenError(f"a lookup table needs at least 2 entries, got {n}")
        lo, hi = value_range if value_range is not None else self.value_range
        rgb, alpha = self.sample(np.linspace(lo, hi, n))
        return np.concatenate([rgb, alpha[:, None]], axis=1).astype(np.float32)

    # ------------------------------------------------------------------------- file format
    def to_dict(self) -> dict[str, Any]:
        """DESIGN.md's TF JSON (version 1); keys this version does not know are kept."""
        out: dict[str, Any] = dict(self.extra)
        out.update(
            {
                "version": TF_FORMAT_VERSION,
                "kind": "1d",
                "color": self._color.tolist(),
                "opacity": self._opacity.tolist(),
                "opacity_unit_distance": self._unit,
            }
        )
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> TransferFunction1D:
        """Read DESIGN.md's TF JSON; errors are VolrenErrors without the file name (callers add it)."""
        check_format_version(data, "transfer function", TF_FORMAT_VERSION, default=TF_FORMAT_VERSION)
        kind = data.get("kind", "1d")
        if kind != "1d":
            raise VolrenError(f"transfer-function kind {kind!r} is not supported here (expected '1d')")
        for key in ("color", "opacity"):
            if key not in data:
                raise VolrenError(f"missing '{key}' list")
        extra = {k: v for k, v in data.items() if k not in _KNOWN_KEYS}
        return cls(data["color"], data["opacity"], data.get("opacity_unit_distance", 1.0), extra)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, TransferFunction1D):
            return NotImplemented
        return (
            np.array_equal(self._color, other._color)
            and np.array_equal(self._opacity, other._opacity)
            and self._unit == other._unit
        )

    __hash__ = None  # type: ignore[assignment]  # mutable

    def __repr__(self) -> str:
        lo, hi = self.value_range
        return (
            f"TransferFunction1D({len(self._color)} colour, {len(self._opacity)} opacity points "
            f"over [{lo:g}, {hi:g}], unit distance {self._unit:g})"
        )


_KNOWN_KEYS = {"version", "kind", "color", "opacity", "opacity_unit_distance"}
