"""Every header field a reader uses is checked before it is used: a bad one is one VolrenError line
naming the file (and, for DICOM, the slice file) and the field, never a crash, a silent misread or
uninitialized memory. SLC and DICOM are read by volren itself; NIfTI's header is checked before
VTK's reader sees the file."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from volren.bench.fuzz.seeds import SPACING as SEED_SPACING
from volren.bench.fuzz.seeds import grid_values, slc_bytes
from volren.bench.fuzz.volume_cases import slc_cases
from volren.errors import VolrenError
from volren.io import load_volume


def fails(path: Path, *fragments: str) -> str:
    with pytest.raises(VolrenError) as info:
        load_volume(path)
    message = str(info.value)
    assert "\n" not in message and message.startswith(f"{path}:"), message
    for fragment in fragments:
        assert fragment in message, message
    return message


# ------------------------------------------------------------------------------------------- SLC

SLC_VALUES = (grid_values() // 8).clip(0, 255).astype(np.uint8)


@pytest.mark.parametrize("compressed", [True, False])
def test_slc_raw_and_run_length_slices(tmp_path, compressed):
    path = tmp_path / "v.slc"
    path.write_bytes(slc_bytes(SLC_VALUES, compressed))
    volume = load_volume(path)
    np.testing.assert_array_equal(volume.values, SLC_VALUES)
    assert volume.spacing == pytest.approx(SEED_SPACING) and volume.origin == (0.0, 0.0, 0.0)


def test_slc_matches_vtks_reader_on_the_real_dataset(shared_data):
    import pyvista as pv
    from vtkmodules.vtkIOImage import vtkSLCReader

    path = shared_data / "uniform" / "neghip.slc"
    reader = vtkSLCReader()
    reader.SetFileName(str(path))
    reader.Update()
    image = pv.wrap(reader.GetOutput())
    expected = np.asarray(image.point_data["SLCImage"]).reshape(tuple(image.dimensions)[::-1])
    volume = load_volume(path)
    assert volume.values.dtype == np.uint8
    np.testing.assert_array_equal(volume.values, expected)
    assert volume.spacing == tuple(image.spacing) and volume.origin == tuple(image.origin)
    assert load_volume(path, scalars="SLCImage").values.shape == (66, 66, 66)
    with pytest.raises(VolrenError, match="no array named 'x'; available: 'SLCImage'"):
        load_volume(path, scalars="x")


SLC_PROBLEMS = {
    "flag-rle-on-raw-slices": "slice 1 of 6 (8x7): no compressed size",
    "flag-raw-on-rle-slices": "36 bytes follow the last of the 6 raw 8x7 slices",
    "run-longer-than-slice": "slice 3 of 6 (8x7): a run of 127 samples at sample 0 goes past the slice's 56",
    "literal-run-past-block": "slice 3 of 6 (8x7): a run of 56 literal bytes at byte 0 goes past the slice's compressed size",
    "repeat-run-without-value": "slice 3 of 6 (8x7): a repeated run at byte 0 has no value byte",
    "runs-short-of-slice": "slice 3 of 6 (8x7): its runs decode to 28 samples, the slice has 56",
    "no-end-marker": "slice 3 of 6 (8x7): its 57 bytes of runs end without the end-of-slice marker",
    "size-past-end": "slice 6 of 6 (8x7) declares 99,999 compressed bytes, only 58 follow",
    "size-negative": "slice 3 of 6 (8x7): compressed size -5 is negative",
    "size-short": "slice 3 of 6 (8x7): a run of 56 literal bytes",
    "size-long": "slice 3 of 6 (8x7): 5 bytes follow the end-of-slice marker",
    "size-huge": "slice 3 of 6 (8x7) declares 99,999,999,999,999,999,999 compressed bytes",
    "icon-huge": "the 99999x99999 icon (3 planes, 29,999,400,003 bytes) runs past the end of the file",
    "icon-negative": "icon size -2x2 is negative",
    "bits-16": "SLC bits per voxel 16",
    "slice-missing": "truncated: slice 6 of 6 (8x7) is missing",
}  # fmt: skip


@pytest.mark.parametrize("case", list(slc_cases()), ids=lambda c: c.name)
def test_slc_what_vtks_reader_trusted(tmp_path, case):
    # vtkSLCReader crashed on five of these and returned uninitialized or misread values on others
    path = tmp_path / "v.slc"
    path.write_bytes(case.files["v.slc"])
    fails(path, SLC_PROBLEMS[case.name.split("/")[1]])


@pytest.mark.parametrize("spacing, problem", [
    ("nan 1 1", "voxel spacing nan 1 1 must be finite numbers"),
    ("0 1 1", "voxel spacing 0 1 1 has a zero entry"),
    ("1 x 1", "voxel spacing '1 x 1' must be three numbers"),
])  # fmt: skip
def test_slc_spacing(tmp_path, spacing, problem):
    text = slc_bytes(SLC_VALUES, True).replace(b"0.5 0.75 1.25", spacing.encode(), 1)
    (tmp_path / "s.slc").write_bytes(text)
    fails(tmp_path / "s.slc", problem)


def test_slc_negative_spacing_mirrors(tmp_path):
    (tmp_path / "m.slc").write_bytes(slc_bytes(SLC_VALUES, True).replace(b"0.5 0.75", b"-0.5 0.75", 1))
    volume = load_volume(tmp_path / "m.slc")
    np.testing.assert_array_equal(volume.values, SLC_VALUES[:, :, ::-1])
    assert volume.spacing[0] == 0.5 and volume.origin[0] == -0.5 * 7


def test_slc_header_words(tmp_path):
    good = slc_bytes(SLC_VALUES, True)
    for old, new, problem in (
        (b"1 6 0 1", b"1 6 0 7", "unknown SLC compression flag 7"),
        (b"1 6 0 1", b"1 x 0 1", "data origin 'x' must be an integer"),
        (b"11111\n8 7 6 8", b"11111\n8 7", "malformed SLC header"),
        (b"2 2 X", b"2 2 Y", "expected the icon size 'width height X'"),
    ):
        (tmp_path / "h.slc").write_bytes(good.replace(old, new, 1))
        fails(tmp_path / "h.slc", problem)
    (tmp_path / "t.slc").write_bytes(b"11111 8 7 6 8 1 1")
    fails(tmp_path / "t.slc", "truncated: the SLC header has 7 of its 12 words")
