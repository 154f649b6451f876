"""The 2D transfer function: colour and opacity over (data value s, gradient magnitude g).

Optical model (DESIGN.md): the same emission-absorption model as the 1D TF with |grad s| as a
second axis. The opacity a(s, g) is that of a slab `opacity_unit_distance` (d_u) thick, so the
extinction is tau = -ln(1 - min(a, 1 - 1e-6)) / d_u and the emission q = c tau.

The TF is a list of widgets, each an opacity bump a_i(s, g) (peak `opacity`) with one colour c_i
(r, g, b in [0, 1], not premultiplied). The formulas, with a = `opacity` the widget's peak:

    gaussian  centre (s0, g0), widths (standard deviations) (ws, wg):
              a_i = a exp(-((s - s0) / ws)^2 / 2 - ((g - g0) / wg)^2 / 2)
    box       value_range [s_lo, s_hi], gradient_range [g_lo, g_hi] (closed intervals):
              a_i = a inside s_lo <= s <= s_hi and g_lo <= g <= g_hi, 0 outside
    triangle  apex value s0, half_width w, gradient_max gm (Kniss's triangle, Levoy's
              isovalue-contour opacity): the half-width grows linearly with the gradient,
              h(g) = w g / gm, reaching w at g = gm, and the opacity falls linearly from the
              centre line s = s0 to the edges:
              a_i = a (1 - |s - s0| / h(g))   for 0 < g <= gm and |s - s0| <= h(g)
              a_i = a                          for g = 0 and s = s0 (the apex)
              a_i = 0                          elsewhere (g < 0, g > gm, or outside the edges)
    1d        a 1D TF as a band over gradient magnitude: color_points [[x, r, g, b], ...] and
              opacity_points [[x, a], ...] (a 1D TF's colour and opacity, piecewise linear,
              constant beyond the ends: c_p(s), a_p(s)), gradient_range [g_lo, g_hi] (closed):
              a_i = a a_p(s)   for g_lo <= g <= g_hi, 0 outside
              c_i = c c_p(s)   (componentwise; its `color` c tints the points' colours)
              With color [1, 1, 1], opacity 1 and the band over [0, gmax] it draws exactly what
              that 1D TF draws (`from_1d`), which is how the editor turns a 1D TF into a 2D one.

Widgets combine per point (a contract the GPU renderer and the reference share):

    a = 1 - prod_i (1 - a_i)                          (independent absorbers)
    c = sum_i a_i c_i / sum_i a_i                     where some a_i > 0;
        the mean c_i of the 1d widgets whose band holds g where every a_i is 0 (as a 1D TF
        has a colour where it is transparent, so colour tables match the 1D TF's there too);
        0 where there is none

The TF is defined on the rectangle value_range x gradient_range = [lo, hi] x [0, gmax] and is
constant beyond its edges, like a 1D TF beyond its end points: `sample` evaluates the widgets at
(clamp(s, lo, hi), clamp(g, 0, gmax)). So a linearly filtered texture of `table` with
clamp-to-edge addressing reproduces the TF outside the rectangle exactly.

Every edit bumps `version`, drawn from the same process-wide counter as TransferFunction1D, so
(version, ...) cache keys never collide across the two kinds.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from volren.errors import VolrenError
from volren.model.file_version import check_format_version
from volren.model.transfer_function import MAX_OPACITY, TF_FORMAT_VERSION, TransferFunction1D
from volren.model.versioned import Versioned

WIDGET_TYPES = ("gaussian", "triangle", "box", "1d")

#: The geometry keys of each widget type, in the order of its dataclass fields.
GEOMETRY_KEYS: Mapping[str, tuple[str, ...]] = MappingProxyType(
    {
        "gaussian": ("center", "width"),
        "triangle": ("value", "half_width", "gradient_max"),
        "box": ("value_range", "gradient_range"),
        "1d": ("color_points", "opacity_points", "gradient_range"),
    }
)
_ALL_GEOMETRY = (
    "center", "width", "value", "half_width", "gradient_max", "value_range", "gradient_range", "color_points",
    "opacity_points",
)  # fmt: skip
#: The keys whose values are lists of control points, not numbers or [lo, hi] pairs.
_POINT_KEYS = ("color_points", "opacity_points")
_EXPECTED_TYPES = "gaussian, triangle, box or 1d"
_WIDGET_KEYS = {"type", "color", "opacity", *_ALL_GEOMETRY}
#: Most widgets a 2D TF may have: renderers evaluate every widget at every sample (or texel), so
#: the cost grows with their number; hand-made 2D TFs have a handful.
MAX_WIDGETS = 1024

_KNOWN_KEYS = {"version", "kind", "value_range", "gradient_range", "widgets", "opacity_unit_distance"}


def _number(value: Any, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise VolrenError(f"{what} must be a number, got {value!r}")
    try:
        number = float(value)
    except OverflowError:  # an integer beyond float64
        number = math.inf
    if not math.isfinite(number):
        raise VolrenError(f"{what} must be finite, got {value!r}")
    return number


def _numbers(value: Any, count: int, what: str) -> tuple[float, ...]:
    if isinstance(value, str | bytes | Mapping) or not isinstance(value, Iterable):
        raise VolrenError(f"{what} must be a list of {count} numbers, got {value!r}")
    items = list(value)
    if len(items) != count:
        raise VolrenError(f"{what} must be a list of {count} numbers, got {value!r}")
    return tuple(_number(v, what) for v in items)


def _interval(value: Any, what: str, non_negative: bool = False) -> tuple[float, float]:
    lo, hi = _numbers(value, 2, what)
    if not lo < hi:
        raise VolrenError(f"{what} must be [lo, hi] with lo < hi, got [{lo:g}, {hi:g}]")
    if non_negative and lo < 0:
        raise VolrenError(f"{what} must not start below 0 (gradient magnitudes), got [{lo:g}, {hi:g}]")
    return lo, hi


@dataclass(frozen=True)
class TFWidget:
    """One widget of a 2D TF: an opacity bump over (value, gradient magnitude) in one colour.

    Build one with `TFWidget.gaussian`, `TFWidget.box`, `TFWidget.triangle` or `TFWidget.from_1d` (or the
    constructor with the geometry fields of its `type`; the others stay None). Geometry is in
    data-value and gradient-magnitude (value per world unit) units; the formulas are in the
    module docstring. `extra` holds JSON keys this version does not know (kept on round trip,
    ignored by ==). Edit with `dataclasses.replace`, which validates again.
    """

    type: str
    color: tuple[float, float, float]
    opacity: float
    #: gaussian: (value, gradient) of the peak
    center: tuple[float, float] | None = None
    #: gaussian: standard deviations (value, gradient), both > 0
    width: tuple[float, float] | None = None
    #: triangle: the value of the apex (at gradient 0)
    value: float | None = None
    #: triangle: value half-width at gradient_max (> 0)
    half_width: float | None = None
    #: triangle: the top of the triangle in gradient magnitude (> 0)
    gradient_max: float | None = None
    #: box: [lo, hi] in value
    value_range: tuple[float, float] | None = None
    #: box and 1d: [lo, hi] in gradient magnitude, 0 <= lo < hi
    gradient_range: tuple[float, float] | None = None
    #: 1d: a 1D TF's colour points ((x, r, g, b), ...), sorted by x
    color_points: tuple[tuple[float, ...], ...] | None = None
    #: 1d: a 1D TF's opacity points ((x, a), ...), sorted by x
    opacity_points: tuple[tuple[float, ...], ...] | None = None
    extra: Mapping[str, Any] = field(default_factory=dict, compare=False, repr=False)

    # ------------------------------------------------------------------------ constructors
    @classmethod
    def gaussian(cls, center: ArrayLike, width: ArrayLike, color: ArrayLike, opacity: float) -> TFWidget:
        return cls("gaussian", color, opacity, center=center, width=width)  # type: ignore[arg-type]

    @classmethod
    def box(
        cls, value_range: ArrayLike, gradient_range: ArrayLike, color: ArrayLike, opacity: float
    ) -> TFWidget:
        return cls("box", color, opacity, value_range=value_range, gradient_range=gradient_range)  # type: ignore[arg-type]

    @classmethod
    def triangle(
        cls, value: float, half_width: float, gradient_max: float, color: ArrayLike, opacity: float
    ) -> TFWidget:
        return cls("triangle", color, opacity, value=value, half_width=half_width, gradient_max=gradient_max)  # type: ignore[arg-type]

    @classmethod
    def from_1d(cls, tf: TransferFunction1D, gradient_range: ArrayLike) -> TFWidget:
        """The 1D TF `tf` as a band over `gradient_range`: within it, what `tf` draws."""
        return cls(
            "1d", (1.0, 1.0, 1.0), 1.0, gradient_range=gradient_range,  # type: ignore[arg-type]
            color_points=tf.color_points, opacity_points=tf.opacity_points,  # type: ignore[arg-type]
        )  # fmt: skip

    def __post_init__(self) -> None:
        if self.type not in WIDGET_TYPES:
            raise VolrenError(f"unknown widget type {self.type!r} (expected {_EXPECTED_TYPES})")
        label = f"{self.type} widget"
        set_ = object.__setattr__
        rgb = _numbers(self.color, 3, f"{label}: color")
        if not all(0.0 <= c <= 1.0 for c in rgb):
            raise VolrenError(f"{label}: color values must lie in [0, 1], got {list(rgb)}")
        set_(self, "color", rgb)
        peak = _number(self.opacity, f"{label}: opacity")
        if not 0.0 <= peak <= 1.0:
            raise VolrenError(f"{label}: opacity must lie in [0, 1], got {peak:g}")
        set_(self, "opacity", peak)
        needed = GEOMETRY_KEYS[self.type]
        for key in _ALL_GEOMETRY:
            present = getattr(self, key) is not None
            if key in needed and not present:
                raise VolrenError(f"{label}: missing {key!r} (a {self.type} needs {', '.join(needed)})")
            if key not in needed and present:
                raise VolrenError(f"{label}: {key!r} does not apply (a {self.type} has {', '.join(needed)})")
        if self.type == "gaussian":
            s0, g0 = _numbers(self.center, 2, f"{label}: center")
            if g0 < 0:
                raise VolrenError(f"{label}: center gradient must be >= 0 (a gradient magnitude), got {g0:g}")
            ws, wg = _numbers(self.width, 2, f"{label}: width")
            if not (ws > 0 and wg > 0):
                raise VolrenError(
                    f"{label}: width (standard deviations) must be positive, got [{ws:g}, {wg:g}]"
                )
            set_(self, "center", (s0, g0))
            set_(self, "width", (ws, wg))
        elif self.type == "box":
            set_(self, "value_range", _interval(self.value_range, f"{label}: value_range"))
            set_(self, "gradient_range", _interval(self.gradient_range, f"{label}: gradient_range", True))
        elif self.type == "1d":
            profile = self._checked_profile(label)
            set_(self, "color_points", tuple(tuple(p) for p in profile.color_points.tolist()))
            set_(self, "opacity_points", tuple(tuple(p) for p in profile.opacity_points.tolist()))
            set_(self, "gradient_range", _interval(self.gradient_range, f"{label}: gradient_range", True))
        else:
            set_(self, "value", _number(self.value, f"{label}: value"))
            for key in ("half_width", "gradient_max"):
                number = _number(getattr(self, key), f"{label}: {key}")
                if not number > 0:
                    raise VolrenError(f"{label}: {key} must be positive, got {number:g}")
                set_(self, key, number)
        set_(self, "extra", dict(self.extra))

    def _checked_profile(self, label: str) -> TransferFunction1D:
        """A 1d widget's points as a 1D TF: checked and sorted by the 1D TF's own rules."""
        try:
            return TransferFunction1D(self.color_points, self.opacity_points)  # type: ignore[arg-type]
        except VolrenError as exc:
            raise VolrenError(f"{label}: {exc}") from None

    # ------------------------------------------------------------------------------ values
    @property
    def geometry(self) -> dict[str, Any]:
        """The geometry of this widget's type as JSON values, e.g. {'center': [s, g], 'width': [...]}."""
        out: dict[str, Any] = {}
        for key in GEOMETRY_KEYS[self.type]:
            value = getattr(self, key)
            if key in _POINT_KEYS:
                out[key] = [list(point) for point in value]
            else:
                out[key] = list(value) if isinstance(value, tuple) else value
        return out

    def profile(self) -> TransferFunction1D:
        """A 1d widget's points as a new 1D TF (c_p and a_p of the module docstring)."""
        if self.type != "1d":
            raise VolrenError(f"a {self.type} widget has no 1D profile")
        return TransferFunction1D(self.color_points, self.opacity_points)  # type: ignore[arg-type]

    def color_at(self, values: ArrayLike) -> NDArray[np.float64]:
        """c_i(s), (..., 3): the widget's colour, which only a 1d widget varies with the value."""
        s = np.asarray(values, dtype=np.float64)
        if self.type != "1d":
            return np.broadcast_to(np.asarray(self.color), s.shape + (3,))
        rgb, _ = self.profile().sample(s)
        return rgb * np.asarray(self.color)

    def in_band(self, gradients: ArrayLike) -> NDArray[np.bool_]:
        """Where a 1d widget's gradient band holds g (False for the other types)."""
        g = np.asarray(gradients, dtype=np.float64)
        if self.type != "1d":
            return np.zeros(g.shape, dtype=bool)
        g_lo, g_hi = self.gradient_range  # type: ignore[misc]
        return (g >= g_lo) & (g <= g_hi)

    def opacity_at(self, values: ArrayLike, gradients: ArrayLike) -> NDArray[np.float64]:
        """a_i(s, g) (not clamped to any range), broadcast over `values` and `gradients`."""
        s, g = np.broadcast_arrays(
            np.asarray(values, dtype=np.float64), np.asarray(gradients, dtype=np.float64)
        )
        peak = self.opacity
        if self.type == "gaussian":
            (s0, g0), (ws, wg) = self.center, self.width  # type: ignore[misc]
            return peak * np.exp(-0.5 * ((s - s0) / ws) ** 2 - 0.5 * ((g - g0) / wg) ** 2)
        if self.type == "box":
            (s_lo, s_hi), (g_lo, g_hi) = self.value_range, self.gradient_range  # type: ignore[misc]
            inside = (s >= s_lo) & (s <= s_hi) & (g >= g_lo) & (g <= g_hi)
            return np.where(inside, peak, 0.0)
        if self.type == "1d":
            _, alpha = self.profile().sample(s)
            return np.where(self.in_band(g), peak * alpha, 0.0)
        s0, w, gm = self.value, self.half_width, self.gradient_max
        d = np.abs(s - s0)  # type: ignore[operator]
        h = w * g / gm  # type: ignore[operator]
        inside = (g >= 0) & (g <= gm) & (d <= h)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # tiny h: masked below
            ramp = np.where(h > 0, 1.0 - d / np.where(h > 0, h, 1.0), 1.0)
        return np.where(inside, peak * ramp, 0.0)

    # ------------------------------------------------------------------------- file format
    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = dict(self.extra)
        out.update({"type": self.type, **self.geometry, "color": list(self.color), "opacity": self.opacity})
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> TFWidget:
        """A widget from its JSON object; keys of other widget types and unknown keys go to `extra`."""
        if not isinstance(data, Mapping):
            raise VolrenError(f"must be a JSON object, got {type(data).__name__}")
        kind = data.get("type")
        if kind is None:
            raise VolrenError(f"missing 'type' ({_EXPECTED_TYPES})")
        if kind not in WIDGET_TYPES:
            raise VolrenError(f"unknown type {kind!r} (expected {_EXPECTED_TYPES})")
        for key in ("color", "opacity", *GEOMETRY_KEYS[kind]):
            if key not in data:
                raise VolrenError(f"{kind} widget: missing {key!r}")
        own = {"type", "color", "opacity", *GEOMETRY_KEYS[kind]}
        geometry = {key: data[key] for key in GEOMETRY_KEYS[kind]}
        extra = {k: v for k, v in data.items() if k not in own}
        return cls(kind, data["color"], data["opacity"], extra=extra, **geometry)


def _nonzero(total: NDArray[np.float64]) -> NDArray[np.float64]:
    """`total` (...) as a divisor (..., 1), 1 where it is 0 (where the numerator is 0 too)."""
    return np.where(total > 0, total, 1.0)[..., None]


class TransferFunction2D(Versioned):
    """Widgets over (value, gradient magnitude) on [lo, hi] x [0, gmax], with change notification."""

    #: The TF's dimension: renderers check it against their capabilities (`KindSupport.tf_dims`).
    dims: ClassVar[int] = 2

    def __init__(
        self,
        value_range: ArrayLike,
        gradient_range: ArrayLike,
        widgets: Iterable[TFWidget] = (),
        opacity_unit_distance: float = 1.0,
        extra: Mapping[str, Any] | None = None,
    ) -> None:
        self._value_range = self._check_value_range(value_range)
        self._gradient_range = self._check_gradient_range(gradient_range)
        self._widgets = self._check_widgets(widgets)
        self._unit = TransferFunction1D._check_unit(opacity_unit_distance)
        self.extra: dict[str, Any] = dict(extra or {})
        super().__init__()

    # --------------------------------------------------------------------------- checks
    @staticmethod
    def _check_value_range(value: ArrayLike) -> tuple[float, float]:
        return _interval(value, "value_range")

    @staticmethod
    def _check_gradient_range(value: ArrayLike) -> tuple[float, float]:
        lo, gmax = _numbers(value, 2, "gradient_range")
        if lo != 0 or not gmax > 0:
            raise VolrenError(f"gradient_range must be [0, gmax] with gmax > 0, got [{lo:g}, {gmax:g}]")
        return 0.0, gmax

    @staticmethod
    def _check_widget(widget: Any, index: int) -> TFWidget:
        if not isinstance(widget, TFWidget):
            raise VolrenError(f"widget {index} must be a TFWidget, got {type(widget).__name__}")
        return widget

    def _index(self, index: int) -> int:
        n = len(self._widgets)
        if isinstance(index, bool) or not isinstance(index, int | np.integer) or not -n <= index < n:
            raise VolrenError(f"no widget {index!r}: the transfer function has {n} widget(s)")
        return int(index) % n

    # ------------------------------------------------------------------------------ state
    @property
    def value_range(self) -> tuple[float, float]:
        """(lo, hi): the value axis of the TF (and of `table`); constant beyond it."""
        return self._value_range

    @property
    def gradient_range(self) -> tuple[float, float]:
        """(0, gmax): the gradient-magnitude axis of the TF (and of `table`); constant beyond it."""
        return self._gradient_range

    @property
    def widgets(self) -> tuple[TFWidget, ...]:
        return tuple(self._widgets)

    @property
    def opacity_unit_distance(self) -> float:
        return self._unit

    # ------------------------------------------------------------------------------ edits
    def add_widget(self, widget: TFWidget) -> int:
        """Append a widget; returns its index."""
        if len(self._widgets) >= MAX_WIDGETS:
            raise VolrenError(f"a 2D transfer function has at most {MAX_WIDGETS} widgets")
        self._widgets.append(self._check_widget(widget, len(self._widgets)))
        self._changed()
        return len(self._widgets) - 1

    def replace_widget(self, index: int, widget: TFWidget) -> None:
        i = self._index(index)
        self._widgets[i] = self._check_widget(widget, i)
        self._changed()

    def remove_widget(self, index: int) -> TFWidget:
        """Remove and return widget `index`."""
        removed = self._widgets.pop(self._index(index))
        self._changed()
        return removed

    def set_widgets(self, widgets: Iterable[TFWidget]) -> None:
        self._widgets = self._check_widgets(widgets)
        self._changed()

    @classmethod
    def _check_widgets(cls, widgets: Iterable[TFWidget]) -> list[TFWidget]:
        checked = [cls._check_widget(w, i) for i, w in enumerate(widgets)]
        if len(checked) > MAX_WIDGETS:
            raise VolrenError(f"a 2D transfer function has at most {MAX_WIDGETS} widgets, got {len(checked)}")
        return checked

    def set_value_range(self, lo: float, hi: float) -> None:
        self._value_range = self._check_value_range((lo, hi))
        self._changed()

    def set_gradient_range(self, gmax: float) -> None:
        """The gradient axis becomes [0, gmax]."""
        self._gradient_range = self._check_gradient_range((0.0, gmax))
        self._changed()

    def set_opacity_unit_distance(self, value: float) -> None:
        self._unit = TransferFunction1D._check_unit(value)
        self._changed()

    def copy(self) -> TransferFunction2D:
        return TransferFunction2D(
            self._value_range, self._gradient_range, self._widgets, self._unit, self.extra
        )

    # ---------------------------------------------------------------------------- sampling
    def sample(
        self, values: ArrayLike, gradients: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Colour (..., 3) and opacity (...) at (value, gradient magnitude) pairs (broadcast).

        The pairs are clamped to the TF's rectangle first; NaN or infinite inputs give opacity 0,
        colour 0. Widgets combine as in the module docstring.
        """
        s, g = np.broadcast_arrays(
            np.asarray(values, dtype=np.float64), np.asarray(gradients, dtype=np.float64)
        )
        bad = ~(np.isfinite(s) & np.isfinite(g))
        lo, hi = self._value_range
        s = np.clip(np.where(bad, lo, s), lo, hi)
        g = np.clip(np.where(bad, 0.0, g), 0.0, self._gradient_range[1])
        transmit = np.ones(s.shape)
        weight = np.zeros(s.shape)
        rgb = np.zeros(s.shape + (3,))
        bands = np.zeros(s.shape)  # 1d widgets whose band holds g, and the sum of their colours
        band_rgb = np.zeros(s.shape + (3,))
        for widget in self._widgets:
            a = widget.opacity_at(s, g)
            color = widget.color_at(s)
            transmit *= 1.0 - a
            weight += a
            rgb += a[..., None] * color
            in_band = widget.in_band(g)
            bands += in_band
            band_rgb += in_band[..., None] * color
        alpha = np.where(bad, 0.0, np.clip(1.0 - transmit, 0.0, 1.0))
        rgb = np.where((weight > 0)[..., None], rgb / _nonzero(weight), band_rgb / _nonzero(bands))
        rgb = np.clip(rgb, 0.0, 1.0)
        rgb[bad] = 0.0
        return rgb, alpha

    def extinction(self, values: ArrayLike, gradients: ArrayLike) -> NDArray[np.float64]:
        """tau(s, g) = -ln(1 - min(a(s, g), 1 - 1e-6)) / opacity_unit_distance, per unit length."""
        _, alpha = self.sample(values, gradients)
        return -np.log1p(-np.minimum(alpha, MAX_OPACITY)) / self._unit

    def table(self, n_values: int = 256, n_gradients: int = 256) -> NDArray[np.float32]:
        """float32 (n_gradients, n_values, 4) [r, g, b, a] (colour not premultiplied) at
        s_i = lo + (hi - lo) i / (n_values - 1), g_j = gmax j / (n_gradients - 1): row j, column i."""
        for name, n in (("n_values", n_values), ("n_gradients", n_gradients)):
            if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 2:
                raise VolrenError(f"a 2D transfer-function table needs {name} >= 2, got {n!r}")
        lo, hi = self._value_range
        s = lo + (hi - lo) * np.arange(n_values) / (n_values - 1)
        g = self._gradient_range[1] * np.arange(n_gradients) / (n_gradients - 1)
        rgb, alpha = self.sample(s[None, :], g[:, None])
        return np.concatenate([rgb, alpha[..., None]], axis=-1).astype(np.float32)

    # ------------------------------------------------------------------------- file format
    def to_dict(self) -> dict[str, Any]:
        """DESIGN.md's TF JSON (version 1, kind 2d); keys this version does not know are kept."""
        out: dict[str, Any] = dict(self.extra)
        out.update(
            {
                "version": TF_FORMAT_VERSION,
                "kind": "2d",
                "value_range": list(self._value_range),
                "gradient_range": list(self._gradient_range),
                "widgets": [w.to_dict() for w in self._widgets],
                "opacity_unit_distance": self._unit,
            }
        )
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> TransferFunction2D:
        """Read a 2D TF's JSON; errors are one-line VolrenErrors without the file name."""
        check_format_version(data, "transfer function", TF_FORMAT_VERSION, default=TF_FORMAT_VERSION)
        kind = data.get("kind")
        if kind != "2d":
            raise VolrenError(f"transfer-function kind {kind!r} is not supported here (expected '2d')")
        for key in ("value_range", "gradient_range", "widgets"):
            if key not in data:
                raise VolrenError(f"2D transfer function: missing {key!r}")
        raw = data["widgets"]
        if not isinstance(raw, list):
            raise VolrenError(f"2D transfer function: 'widgets' must be a list, got {type(raw).__name__}")
        if len(raw) > MAX_WIDGETS:
            raise VolrenError(f"2D transfer function: {len(raw)} widgets; at most {MAX_WIDGETS}")
        widgets = []
        for i, item in enumerate(raw):
            try:
                widgets.append(TFWidget.from_dict(item))
            except VolrenError as exc:
                raise VolrenError(f"widget {i}: {exc}") from None
        extra = {k: v for k, v in data.items() if k not in _KNOWN_KEYS}
        return cls(
            data["value_range"],
            data["gradient_range"],
            widgets,
            data.get("opacity_unit_distance", 1.0),
            extra,
        )

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, TransferFunction2D):
            return NotImplemented
        return (
            self._value_range == other._value_range
            and self._gradient_range == other._gradient_range
            and self._widgets == other._widgets
            and self._unit == other._unit
        )

    __hash__ = None  # type: ignore[assignment]  # mutable

    def __repr__(self) -> str:
        lo, hi = self._value_range
        kinds = ", ".join(w.type for w in self._widgets) or "no widgets"
        return (
            f"TransferFunction2D({kinds} over [{lo:g}, {hi:g}] x [0, {self._gradient_range[1]:g}], "
            f"unit distance {self._unit:g})"
        )


#: Either kind of transfer function.
TransferFunction = TransferFunction1D | TransferFunction2D


def transfer_function_from_dict(data: Mapping[str, Any]) -> TransferFunction1D | TransferFunction2D:
    """Read DESIGN.md's TF JSON of either kind ('kind': '1d', the default, or '2d')."""
    check_format_version(data, "transfer function", TF_FORMAT_VERSION, default=TF_FORMAT_VERSION)
    kind = data.get("kind", "1d")
    if kind == "1d":
        return TransferFunction1D.from_dict(data)
    if kind == "2d":
        return TransferFunction2D.from_dict(data)
    raise VolrenError(f"unknown transfer-function kind {kind!r} (expected '1d' or '2d')")
