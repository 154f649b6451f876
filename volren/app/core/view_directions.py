"""The six view directions of ParaView's camera toolbar ("Set view direction to +X", ...), no Qt.

Why these view-ups: ParaView's buttons look along +-X and +-Y with Z up and along +-Z with Y up,
and people coming from it expect the same picture. Unlike ParaView's buttons, which also refit
the camera, the camera here keeps its distance, view angle and parallel scale: the data stays as
large as the person zoomed it, only seen from another side. The camera looks at the centre of the
bounds it is given (the cropped volume's, what is drawn).

Patient directions (A/P/L/R/S/I) are not offered: volumes keep no patient orientation (a file's
direction matrix is dropped at load, with a note), so there is nothing to map them from.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from volren.errors import VolrenError
from volren.model.camera import Camera, Vec3


@dataclass(frozen=True)
class ViewDirection:
    """Look along `direction` (a world axis, from the camera toward the data) with `view_up` up."""

    name: str
    direction: Vec3
    view_up: Vec3

    @property
    def description(self) -> str:
        """The action's tooltip: what it looks along and what is up."""
        up = "Z" if self.view_up[2] else "Y"
        return f"Set view direction to {self.name} ({up} up)"


#: ParaView's order and view-ups.
VIEW_DIRECTIONS: tuple[ViewDirection, ...] = (
    ViewDirection("+X", (1.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
    ViewDirection("-X", (-1.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
    ViewDirection("+Y", (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)),
    ViewDirection("-Y", (0.0, -1.0, 0.0), (0.0, 0.0, 1.0)),
    ViewDirection("+Z", (0.0, 0.0, 1.0), (0.0, 1.0, 0.0)),
    ViewDirection("-Z", (0.0, 0.0, -1.0), (0.0, 1.0, 0.0)),
)


def view_direction(name: str) -> ViewDirection:
    """The direction called `name` ("+X" ... "-Z")."""
    for view in VIEW_DIRECTIONS:
        if view.name == name:
            return view
    raise VolrenError(f"unknown view direction {name!r}; expected one of {[v.name for v in VIEW_DIRECTIONS]}")


def look_along(camera: Camera, view: ViewDirection, bounds: Sequence[float]) -> Camera:
    """`camera` turned to look along `view` at the centre of `bounds`, at its current distance,
    with its view angle, projection and parallel scale; clipping range reset on `bounds`."""
    b = np.asarray(bounds, dtype=np.float64)
    if b.shape != (6,) or not np.all(np.isfinite(b)) or np.any(b[1::2] < b[0::2]):
        raise VolrenError(f"cannot look at bounds {tuple(bounds)}")
    centre = (b[0::2] + b[1::2]) / 2.0
    position = centre - camera.distance * np.asarray(view.direction)
    turned = replace(camera, focal_point=tuple(centre), position=tuple(position), view_up=view.view_up)
    return turned.reset_clipping_range(bounds)
