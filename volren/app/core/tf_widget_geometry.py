"""What the 2D TF editor does to a widget's geometry: outlines, handles, moves and resizes (no Qt).

Why: the editor's canvas only maps pixels to (value, gradient magnitude) and back; every rule
about what a drag means for a Gaussian, a triangle or a box lives here, in data units, where it
can be tested without widgets. All functions return new `TFWidget`s (they are frozen).

What is drawn and dragged (s = data value, g = gradient magnitude):

- gaussian: the ellipse at `GAUSSIAN_EXTENT` standard deviations (opacity e^-2 = 13.5 % of the
  peak there) and its bounding box's corners and edge midpoints as handles; a handle resizes
  symmetrically about the centre (the widget has no other shape).
- box: its rectangle; an edge handle moves that edge, a corner handle the two edges it joins.
- triangle: apex (s0, 0), top corners (s0 -+ w, gm); the top corners set the half-width and the
  height, the top edge's midpoint the height only. The apex stays on g = 0 (the model's
  triangle has no other apex), so moving it changes the value only.
- 1d (a 1D TF as a band over gradient magnitude): the rectangle from its first to its last
  control point in value over its gradient band, handled like a box: a move shifts every point
  and the band, a left or right handle stretches the points linearly over the new value span,
  the top and bottom handles move the band's edges.

Sizes never fall below the `minimum` the caller passes (a small fraction of the axes), and
nothing moves below g = 0.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from volren.model.transfer_function_2d import TFWidget

Point = tuple[float, float]

#: A Gaussian is drawn (and hit) within this many standard deviations of its centre.
GAUSSIAN_EXTENT = 2.0
#: Segments of a Gaussian's outline.
ELLIPSE_SEGMENTS = 48

_BOX_HANDLES = ("bottom_left", "bottom", "bottom_right", "right", "top_right", "top", "top_left", "left")
_TRIANGLE_HANDLES = ("top_left", "top", "top_right")


def _point_span(widget: TFWidget) -> Point:
    """(first, last) control-point value of a 1d widget, colour and opacity points together."""
    xs = [p[0] for p in widget.color_points] + [p[0] for p in widget.opacity_points]  # type: ignore[union-attr]
    return (min(xs), max(xs))


def center(widget: TFWidget) -> Point:
    """The point a move drags: the Gaussian's peak, the box's (or 1d band's) centre, the triangle's centroid."""
    if widget.type == "gaussian":
        return widget.center  # type: ignore[return-value]
    if widget.type in ("box", "1d"):
        s_lo, s_hi, g_lo, g_hi = _extent(widget)
        return (0.5 * (s_lo + s_hi), 0.5 * (g_lo + g_hi))
    return (widget.value, 2.0 * widget.gradient_max / 3.0)  # type: ignore[operator, return-value]


def _extent(widget: TFWidget) -> tuple[float, float, float, float]:
    """(s_lo, s_hi, g_lo, g_hi): the box the outline spans."""
    if widget.type == "gaussian":
        (s0, g0), (ws, wg) = widget.center, widget.width  # type: ignore[misc]
        e = GAUSSIAN_EXTENT
        return (s0 - e * ws, s0 + e * ws, g0 - e * wg, g0 + e * wg)
    if widget.type == "box":
        (s0, s1), (g0, g1) = widget.value_range, widget.gradient_range  # type: ignore[misc]
        return (s0, s1, g0, g1)
    if widget.type == "1d":
        return (*_point_span(widget), *widget.gradient_range)  # type: ignore[return-value, misc]
    s0, w, gm = widget.value, widget.half_width, widget.gradient_max
    return (s0 - w, s0 + w, 0.0, gm)  # type: ignore[operator, return-value]


def outline(widget: TFWidget) -> list[Point]:
    """The closed polygon drawn for the widget (data units, first point not repeated)."""
    if widget.type == "gaussian":
        (s0, g0), (ws, wg) = widget.center, widget.width  # type: ignore[misc]
        angles = np.linspace(0.0, 2.0 * math.pi, ELLIPSE_SEGMENTS, endpoint=False)
        e = GAUSSIAN_EXTENT
        return [(s0 + e * ws * math.cos(a), g0 + e * wg * math.sin(a)) for a in angles]
    s_lo, s_hi, g_lo, g_hi = _extent(widget)
    if widget.type in ("box", "1d"):
        return [(s_lo, g_lo), (s_hi, g_lo), (s_hi, g_hi), (s_lo, g_hi)]
    return [(widget.value, 0.0), (s_hi, g_hi), (s_lo, g_hi)]  # type: ignore[list-item]


def handles(widget: TFWidget) -> dict[str, Point]:
    """Handle name -> position (data units)."""
    s_lo, s_hi, g_lo, g_hi = _extent(widget)
    s_mid, g_mid = 0.5 * (s_lo + s_hi), 0.5 * (g_lo + g_hi)
    every = {
        "bottom_left": (s_lo, g_lo),
        "bottom": (s_mid, g_lo),
        "bottom_right": (s_hi, g_lo),
        "right": (s_hi, g_mid),
        "top_right": (s_hi, g_hi),
        "top": (s_mid, g_hi),
        "top_left": (s_lo, g_hi),
        "left": (s_lo, g_mid),
    }
    names = _TRIANGLE_HANDLES if widget.type == "triangle" else _BOX_HANDLES
    return {name: every[name] for name in names}


def contains(widget: TFWidget, s: float, g: float) -> bool:
    """Whether (s, g) lies inside the drawn outline (where a click selects the widget)."""
    if widget.type == "gaussian":
        (s0, g0), (ws, wg) = widget.center, widget.width  # type: ignore[misc]
        e = GAUSSIAN_EXTENT
        return ((s - s0) / (e * ws)) ** 2 + ((g - g0) / (e * wg)) ** 2 <= 1.0
    s_lo, s_hi, g_lo, g_hi = _extent(widget)
    if widget.type in ("box", "1d"):
        return s_lo <= s <= s_hi and g_lo <= g <= g_hi
    w, gm = widget.half_width, widget.gradient_max
    return 0.0 <= g <= gm and abs(s - widget.value) <= w * g / gm  # type: ignore[operator]


def moved(widget: TFWidget, ds: float, dg: float) -> TFWidget:
    """The widget shifted by (ds, dg); it stops at g = 0 (a triangle moves along s only)."""
    if widget.type == "gaussian":
        s0, g0 = widget.center  # type: ignore[misc]
        return replace(widget, center=(s0 + ds, max(g0 + dg, 0.0)))
    if widget.type == "box":
        (s0, s1), (g0, g1) = widget.value_range, widget.gradient_range  # type: ignore[misc]
        dg = max(dg, -g0)
        return replace(widget, value_range=(s0 + ds, s1 + ds), gradient_range=(g0 + dg, g1 + dg))
    if widget.type == "1d":
        g0, g1 = widget.gradient_range  # type: ignore[misc]
        dg = max(dg, -g0)
        return _points_mapped(replace(widget, gradient_range=(g0 + dg, g1 + dg)), lambda x: x + ds)
    return replace(widget, value=widget.value + ds)  # type: ignore[operator]


def _points_mapped(widget: TFWidget, new_x: Callable[[float], float]) -> TFWidget:
    """A 1d widget with every control point's value x moved to new_x(x), colours and opacities kept."""
    return replace(
        widget,
        color_points=[(new_x(x), *rest) for x, *rest in widget.color_points],  # type: ignore[union-attr]
        opacity_points=[(new_x(x), *rest) for x, *rest in widget.opacity_points],  # type: ignore[union-attr]
    )


def _resized_band(widget: TFWidget, handle: str, s: float, g: float, minimum: Point) -> TFWidget:
    """A 1d widget's resize: its value span as a box's, its points stretched linearly onto it."""
    old_lo, old_hi, g_lo, g_hi = _extent(widget)
    as_box = resized(TFWidget.box((old_lo, max(old_hi, old_lo + minimum[0])), (g_lo, g_hi), widget.color, 0.0),
                     handle, s, g, minimum)  # fmt: skip
    (new_lo, new_hi), band = as_box.value_range, as_box.gradient_range  # type: ignore[misc]
    scale = (new_hi - new_lo) / (old_hi - old_lo) if old_hi > old_lo else 0.0
    return _points_mapped(replace(widget, gradient_range=band), lambda x: new_lo + (x - old_lo) * scale)


def resized(widget: TFWidget, handle: str, s: float, g: float, minimum: Point) -> TFWidget:
    """The widget with `handle` dragged to (s, g); sizes stay at least `minimum` (value, gradient)."""
    min_s, min_g = minimum
    if handle not in handles(widget):
        raise ValueError(f"a {widget.type} widget has no handle {handle!r}")
    if widget.type == "1d":
        return _resized_band(widget, handle, s, g, minimum)
    horizontal = "left" in handle or "right" in handle
    vertical = "top" in handle or "bottom" in handle
    if widget.type == "gaussian":
        (s0, g0), (ws, wg) = widget.center, widget.width  # type: ignore[misc]
        e = GAUSSIAN_EXTENT
        if horizontal:
            ws = max(abs(s - s0) / e, min_s)
        if vertical:
            wg = max(abs(g - g0) / e, min_g)
        return replace(widget, width=(ws, wg))
    if widget.type == "box":
        (s_lo, s_hi), (g_lo, g_hi) = widget.value_range, widget.gradient_range  # type: ignore[misc]
        if "left" in handle:
            s_lo = min(s, s_hi - min_s)
        if "right" in handle:
            s_hi = max(s, s_lo + min_s)
        if "bottom" in handle:
            g_lo = max(min(g, g_hi - min_g), 0.0)
            g_hi = max(g_hi, g_lo + min_g)
        if "top" in handle:
            g_hi = max(g, g_lo + min_g)
        return replace(widget, value_range=(s_lo, s_hi), gradient_range=(g_lo, g_hi))
    half_width, top = widget.half_width, max(g, min_g)
    if horizontal:
        half_width = max(abs(s - widget.value), min_s)  # type: ignore[operator]
    return replace(widget, half_width=half_width, gradient_max=top)


# ---------------------------------------------------------------------------- new widgets
def new_widget(
    kind: str, value_range: Point, gradient_max: float, color: tuple[float, float, float], opacity: float
) -> TFWidget:
    """A widget of `kind` in the middle of the TF's axes, sized relative to them."""
    lo, hi = value_range
    span, mid = hi - lo, 0.5 * (lo + hi)
    if kind == "gaussian":
        return TFWidget.gaussian((mid, 0.5 * gradient_max), (span / 16.0, gradient_max / 8.0), color, opacity)
    if kind == "triangle":
        return TFWidget.triangle(mid, span / 8.0, 0.75 * gradient_max, color, opacity)
    if kind == "box":
        return TFWidget.box(
            (mid - span / 10.0, mid + span / 10.0), (0.35 * gradient_max, 0.65 * gradient_max), color, opacity
        )
    raise ValueError(f"unknown widget type {kind!r} (expected gaussian, triangle or box)")


def placed_gaussian(
    value: float,
    gradient: float,
    value_range: Point,
    gradient_max: float,
    color: tuple[float, float, float],
    opacity: float,
) -> TFWidget:
    """A small Gaussian at a probed (value, gradient magnitude): 1/40 of the value axis and 1/20 of
    the gradient axis wide (a constant default width; Real-Time Volume Graphics, section 10.6)."""
    lo, hi = value_range
    return TFWidget.gaussian(
        (value, max(gradient, 0.0)), ((hi - lo) / 40.0, gradient_max / 20.0), color, opacity
    )


def boundary_triangle(value_range: Point, gradient_max: float) -> TFWidget:
    """The first widget of a new 2D TF: a triangle over the upper part of the value range, the
    book's boundary-emphasis shape (opaque where the gradient is high, nothing in homogeneous
    regions), reaching to the top of the gradient axis."""
    lo, hi = value_range
    span = hi - lo
    return TFWidget.triangle(lo + 0.7 * span, 0.15 * span, gradient_max, (1.0, 0.85, 0.7), 0.8)
