"""Patient orientation (issue 23, A/P/L/R/S/I views): which anatomical side +x, +y, +z point to,
read from DICOM and NRRD, and the anatomical camera views."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from volren.app.core.view_directions import anatomical_view
from volren.errors import VolrenWarning
from volren.io import load_volume
from volren.model.anatomy import patient_axes


def columns(*vectors) -> np.ndarray:
    return np.column_stack(vectors).astype(float)


@pytest.mark.parametrize(
    "direction, space, flips, expected",
    [
        (None, "LPS", (False, False, False), ("L", "P", "S")),
        (None, "RAS", (False, False, False), ("R", "A", "S")),
        (
            columns([0, 1, 0], [0, 0, -1], [-1, 0, 0]),
            "LPS",
            (False, False, False),
            ("P", "I", "R"),
        ),  # sagittal
        (columns([1, 0, 0], [0, 0, -1], [0, 1, 0]), "LPS", (False, False, False), ("L", "I", "P")),  # coronal
        (None, "LPS", (True, False, True), ("R", "P", "I")),  # axes reversed at load
        (columns([0.8, 0.6, 0], [-0.6, 0.8, 0], [0, 0, 1]), "LPS", (False, False, False), None),  # oblique
        (columns([1, 0, 0], [1, 0, 0], [0, 0, 1]), "LPS", (False, False, False), None),  # not a permutation
        (None, None, (False, False, False), None),  # no patient system
        (None, "XYZ", (False, False, False), None),
    ],
)
def test_patient_axes_follow_the_direction_matrix_and_refuse_oblique_images(
    direction, space, flips, expected
):
    assert patient_axes(direction, space, flips) == expected


def test_a_dicom_series_lies_in_lps(tmp_path):
    from volren.testing.dicom_series import write_series

    values = np.arange(4 * 5 * 6, dtype=np.int16).reshape(4, 5, 6)
    write_series(tmp_path / "s", values, (0.5, 0.5, 1.0), (0.0, 0.0, 0.0))
    assert load_volume(tmp_path / "s").patient_axes == ("L", "P", "S")


@pytest.mark.parametrize(
    "space, directions, expected",
    [
        ("left-posterior-superior", "(0,1,0) (0,0,-1) (-1,0,0)", ("P", "I", "R")),
        ("RAS", "(1,0,0) (0,1,0) (0,0,1)", ("R", "A", "S")),
        ("left-posterior-superior", "(0.8,0.6,0) (-0.6,0.8,0) (0,0,1)", None),
        ("3D-right-handed", "(1,0,0) (0,1,0) (0,0,1)", None),
    ],
)
def test_nrrd_names_its_space(tmp_path, space, directions, expected):
    values = np.arange(4 * 5 * 6, dtype=np.float32).reshape(4, 5, 6)
    header = (f"NRRD0004\ntype: float\ndimension: 3\nsizes: 6 5 4\nspace: {space}\nspace directions: {directions}\n"
              "endian: little\nencoding: raw\n\n")  # fmt: skip
    (tmp_path / "v.nrrd").write_bytes(header.encode() + values.tobytes())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", VolrenWarning)  # "ignored the direction matrix": drawn axis-aligned
        volume = load_volume(tmp_path / "v.nrrd")
    assert volume.patient_axes == expected


def test_anatomical_views_look_from_the_named_side_with_slicers_view_up():
    lps = ("L", "P", "S")
    anterior = anatomical_view("A", lps)  # anterior is -y in LPS: the camera there looks toward +y
    assert anterior.direction == (0.0, 1.0, 0.0) and anterior.view_up == (0.0, 0.0, 1.0)
    left = anatomical_view("L", lps)
    assert left.direction == (-1.0, 0.0, 0.0) and left.view_up == (0.0, 0.0, 1.0)
    superior = anatomical_view("S", lps)
    assert superior.direction == (0.0, 0.0, -1.0) and superior.view_up == (0.0, -1.0, 0.0)  # the front up
    assert "patient's superior side (A up)" in superior.description
    sagittal = anatomical_view("A", ("P", "I", "R"))  # anterior is -x here
    assert sagittal.direction == (1.0, 0.0, 0.0) and sagittal.view_up == (0.0, -1.0, 0.0)
