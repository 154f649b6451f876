"""Which way the patient lies in a volume's world axes: the anatomical letter (L/R, A/P, S/I) that
+x, +y and +z point toward, for data read from a format with a patient coordinate system.

DICOM's patient system is LPS (+x toward the patient's left, +y posterior, +z superior); NRRD
names its own ("left-posterior-superior", "RAS", ...). volren draws every grid axis-aligned, its
x, y, z along the image's columns, rows and slices, so the letters come from the image's direction
matrix, and only when that matrix is a signed permutation (axial, coronal or sagittal images, in
any order or sense): an oblique image has no anatomical axis along x, y or z, and a label there
would be wrong, which is worse for a clinician than no label.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

#: Each letter and the one opposite it.
OPPOSITE = {"L": "R", "R": "L", "A": "P", "P": "A", "S": "I", "I": "S"}
#: NRRD's 'space' names of patient systems (3D Slicer writes the long ones). Left-handed LAS is
#: left out: VTK's reader mirrors its rows, and a label that might be mirrored is not given.
NRRD_SPACES = {
    "left-posterior-superior": "LPS", "lps": "LPS",
    "right-anterior-superior": "RAS", "ras": "RAS",
}  # fmt: skip
#: How far from 0 or 1 a direction cosine may be and still count as along an axis.
TOLERANCE = 1e-3


def patient_axes(direction: ArrayLike | None, space: str | None,
                 flips: Sequence[bool] = (False, False, False)) -> tuple[str, str, str] | None:  # fmt: skip
    """The letters +x, +y, +z point toward, or None (no patient system, or an oblique image).

    `direction`'s columns are the image axes in the patient system named by `space` (e.g. "LPS":
    its +x is L); `flips` says which axes volren reversed at load (a negative spacing)."""
    if space is None or len(space) != 3 or any(letter not in OPPOSITE for letter in space):
        return None
    matrix = np.eye(3) if direction is None else np.asarray(direction, dtype=np.float64)
    if matrix.shape != (3, 3) or not np.all(np.isfinite(matrix)):
        return None
    letters, used = [], set()
    for axis in range(3):
        column = matrix[:, axis]
        along = int(np.argmax(np.abs(column)))
        others = np.delete(column, along)
        if abs(abs(column[along]) - 1.0) > TOLERANCE or np.any(np.abs(others) > TOLERANCE):
            return None
        if along in used:  # two image axes along one patient axis: not a permutation
            return None
        used.add(along)
        positive = (column[along] > 0) != bool(flips[axis])
        letters.append(space[along] if positive else OPPOSITE[space[along]])
    return letters[0], letters[1], letters[2]
