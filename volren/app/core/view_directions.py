"""The six view directions of ParaView's camera toolbar ("Set view direction to +X", ...), no Qt.

Why these view-ups: ParaView's buttons look along +-X and +-Y with Z up and along +-Z with Y up,
and people coming from it expect the same picture. Unlike ParaView's buttons, which also refit
the camera, the camera here keeps its distance, view angle and parallel scale: the data stays as
large as the person zoomed it, only seen from another side. The camera looks at the centre of the
bounds it is given (the cropped volume's, what is drawn).

Where the data knows how the patient lies (`Volume.patient_axes`: DICOM, NRRD in LPS or RAS, not
oblique), the six anatomical views of 3D Slicer's 3D view come too: "A" puts the camera at the
patient's anterior looking across, with the head (S) up for A, P, L and R and the front (A) up for
S and I.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from volren.errors import VolrenError
from volren.model.anatomy import OPPOSITE
from volren.model.camera import Camera, Vec3


@dataclass(frozen=True)
class ViewDirection:
    """Look along `direction` (a world axis, from the camera toward the data) with `view_up` up."""

    name: str
    direction: Vec3
    view_up: Vec3
    tooltip: str = ""

    @property
    def description(self) -> str:
        """The action's tooltip: what it looks along and what is up."""
        if self.tooltip:
            return self.tooltip
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


#: The anatomical views, in 3D Slicer's order, and the side each looks from.
ANATOMICAL_SIDES = {
    "A": "anterior",
    "P": "posterior",
    "L": "left",
    "R": "right",
    "S": "superior",
    "I": "inferior",
}


def _toward(letter: str, patient_axes: Sequence[str]) -> tuple[float, float, float]:
    """The world unit vector pointing toward the patient's `letter` side."""
    for axis, named in enumerate(patient_axes):
        if named in (letter, OPPOSITE[letter]):
            vector = [0.0, 0.0, 0.0]
            vector[axis] = 1.0 if named == letter else -1.0
            return vector[0], vector[1], vector[2]
    raise VolrenError(f"patient axes {tuple(patient_axes)} do not include {letter} or {OPPOSITE[letter]}")


def anatomical_view(letter: str, patient_axes: Sequence[str]) -> ViewDirection:
    """The view from the patient's `letter` side (A, P, L, R, S or I), for data whose +x, +y, +z
    point toward `patient_axes`."""
    if letter not in ANATOMICAL_SIDES:
        raise VolrenError(f"unknown anatomical view {letter!r}; expected one of {list(ANATOMICAL_SIDES)}")
    toward = np.asarray(_toward(letter, patient_axes))
    up_letter = "A" if letter in "SI" else "S"
    return ViewDirection(letter, tuple(-toward), _toward(up_letter, patient_axes),
                         f"View from the patient's {ANATOMICAL_SIDES[letter]} side ({up_letter} up)")  # fmt: skip


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
