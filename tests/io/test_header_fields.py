"""Every header field a reader uses is checked before it is used: a bad one is one VolrenError line
naming the file (and, for DICOM, the slice file) and the field, never a crash, a silent misread or
uninitialized memory. SLC and DICOM are read by volren itself; NIfTI's header is checked before
VTK's reader sees the file."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from benchmarks.fuzz.seeds import SPACING as SEED_SPACING
from benchmarks.fuzz.seeds import grid_values, slc_bytes
from benchmarks.fuzz.volume_cases import slc_cases
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


# ----------------------------------------------------------------------------------------- DICOM

from benchmarks.fuzz.volume_cases import _elements, set_element  # noqa: E402
from volren.testing.dicom_series import element, write_series  # noqa: E402

DCM_SPACING = (0.5, 0.75, 2.0)
DCM_VALUES = (np.arange(4 * 5 * 7, dtype=np.int16).reshape(4, 5, 7) * 7 - 50).astype(np.int16)
US = lambda v: int(v).to_bytes(2, "little")  # noqa: E731


def series(tmp_path: Path, values: np.ndarray = DCM_VALUES, name: str = "series") -> list[Path]:
    return write_series(tmp_path / name, values, DCM_SPACING, (0.0, 0.0, 0.0))


def edit(path: Path, tag: tuple[int, int], value: bytes, length: int | None = None) -> None:
    path.write_bytes(set_element(path.read_bytes(), tag, value, length))


@pytest.mark.parametrize("tag, value, problem", [
    ((0x28, 0x10), US(3), "its pixel element holds 70 bytes, but Columns x Rows x BitsAllocated/8 = 7 x 3 x 2 = 42"),
    ((0x28, 0x11), US(0), "Rows 5 and Columns 0 must both be present and positive"),
    ((0x28, 0x100), US(12), "BitsAllocated 12: volren reads 8- and 16-bit DICOM pixels only"),
    ((0x28, 0x100), US(0), "BitsAllocated 0"),
    ((0x28, 0x02), US(3), "SamplesPerPixel 3: volren reads one sample per pixel"),
    ((0x28, 0x02), US(0), "SamplesPerPixel 0"),
    ((0x28, 0x101), US(40), "BitsStored 40 must be 1 to BitsAllocated (16)"),
    ((0x28, 0x103), US(7), "PixelRepresentation 7 must be 0 (unsigned) or 1 (signed)"),
    ((0x28, 0x30), b"nan\\1 ", "PixelSpacing 'nan\\\\1' must be finite"),
    ((0x28, 0x30), b"0\\1 ", "PixelSpacing 0\\1 must be positive"),
    ((0x28, 0x30), b"1 ", "PixelSpacing '1' must be 2 numbers"),
    ((0x18, 0x50), b"0 ", "SliceThickness 0 must be positive"),
    ((0x18, 0x50), b"inf ", "SliceThickness 'inf' must be finite"),
    ((0x20, 0x32), b"nan\\0\\0 ", "ImagePositionPatient 'nan\\\\0\\\\0' must be finite"),
    ((0x20, 0x32), b"1\\2 ", "ImagePositionPatient '1\\\\2' must be 3 numbers"),
    ((0x20, 0x37), b"0\\0\\0\\0\\1\\0 ", "ImageOrientationPatient 0\\0\\0\\0\\1\\0 has a zero direction"),
    ((0x20, 0x37), b"1\\0\\0\\1\\0\\0 ", "ImageOrientationPatient 1\\0\\0\\1\\0\\0: its row and column directions are not perpendicular"),
    ((0x28, 0x1053), b"nan ", "RescaleSlope 'nan' must be finite"),
    ((0x28, 0x1053), b"0 ", "RescaleSlope 0 would make every value the intercept"),
    ((0x28, 0x1052), b"-inf", "RescaleIntercept '-inf' must be finite"),
    ((0x2, 0x10), b"1.2.840.10008.1.2.4.50", "compressed pixel data (JPEG Baseline (Process 1)) is not supported"),
    ((0x2, 0x10), b"garbage\0", "unknown transfer syntax 'garbage'"),
])  # fmt: skip
def test_dicom_field_refused_naming_the_slice(tmp_path, tag, value, problem):
    paths = series(tmp_path)
    edit(paths[2], tag, value)
    fails(tmp_path / "series", f"slice slice002.dcm: {problem}")


def test_dicom_pixel_element_must_match_the_header(tmp_path):
    paths = series(tmp_path)
    data = paths[2].read_bytes()
    *_, (_, _, _, start, end) = _elements(data)
    pixels = data[start:end]
    for content, problem in (
        (set_element(data, (0x7FE0, 0x10), pixels[:35]), "its pixel element holds 35 bytes, but"),
        (set_element(data, (0x7FE0, 0x10), pixels[:-1]), "its pixel element holds 69 bytes, but"),
        (set_element(data, (0x7FE0, 0x10), pixels + bytes(2)), "its pixel element holds 72 bytes, but"),
        (set_element(data, (0x7FE0, 0x10), pixels, 2 * len(pixels)), "truncated: its pixel element declares 140 bytes, the file holds 70"),
        (data[: start - 12], "no pixel data after its 7x5 header (truncated?)"),
        (b"", "empty file (0 bytes)"),
        (bytes(range(256)) * 4, "not a DICOM image"),
        (data[:300], "not a DICOM image"),
    ):  # fmt: skip
        paths[2].write_bytes(content)
        fails(tmp_path / "series", f"slice slice002.dcm: {problem}")


def test_dicom_duplicated_slice_is_refused(tmp_path):
    paths = series(tmp_path)
    (tmp_path / "series" / "zz.dcm").write_bytes(paths[1].read_bytes())
    fails(tmp_path / "series", "two slices at the same position: slice001.dcm and zz.dcm are both at 0\\0\\2")


@pytest.mark.parametrize("slope", ["1e39", "-1e-50", "1e300"])
def test_dicom_rescale_outside_float32_is_read_not_crashed(tmp_path, slope):
    # vtkDICOMImageReader died (SIGSEGV, an uncaught C++ exception) parsing these slopes
    paths = series(tmp_path)
    for path in paths:
        edit(path, (0x28, 0x1053), slope.encode() + (b" " if len(slope) % 2 else b""))
    volume = load_volume(tmp_path / "series")
    assert volume.values.dtype == np.float64
    np.testing.assert_array_equal(volume.values, DCM_VALUES.astype(np.float64) * float(slope))


def test_dicom_rescale_past_float64_is_refused(tmp_path):
    paths = series(tmp_path)
    edit(paths[3], (0x28, 0x1053), b"1e307 ")
    fails(
        tmp_path / "series",
        "slice slice003.dcm: RescaleSlope 1e+307 and RescaleIntercept 0 take its values past the largest float",
    )


def test_dicom_rescale_is_applied_per_slice(tmp_path):
    # one fractional slope among integer ones: vtkDICOMImageReader overran its buffer (double free)
    paths = series(tmp_path)
    edit(paths[1], (0x28, 0x1053), b"0.5 ")
    volume = load_volume(tmp_path / "series")
    expected = DCM_VALUES.astype(np.float32)
    expected[1] *= 0.5
    assert volume.values.dtype == np.float32
    np.testing.assert_array_equal(volume.values, expected)
    for path in paths:
        edit(path, (0x28, 0x1053), b"2 ")
        edit(path, (0x28, 0x1052), b"-1024 ")
    volume = load_volume(tmp_path / "series")
    assert volume.values.dtype == np.int16
    np.testing.assert_array_equal(volume.values, DCM_VALUES * 2 - 1024)
    assert any("applied the DICOM rescale v * 2 + -1024 (as int16)" in n for n in volume.notes)


def test_dicom_8_bit_with_an_odd_pixel_count(tmp_path):
    values = (np.arange(3 * 5 * 7) % 251).astype(np.uint8).reshape(3, 5, 7)  # 35 pixels a slice: one pad byte
    paths = series(tmp_path, values.astype(np.int16))
    for path, plane in zip(paths, values):
        for tag, v in (((0x28, 0x100), 8), ((0x28, 0x101), 8), ((0x28, 0x102), 7), ((0x28, 0x103), 0)):
            edit(path, tag, US(v))
        edit(path, (0x7FE0, 0x10), plane.tobytes() + b"\0")
    volume = load_volume(tmp_path / "series")
    assert volume.values.dtype == np.uint8
    np.testing.assert_array_equal(volume.values, values)


def test_dicom_geometry_from_the_positions(tmp_path):
    # SliceThickness 2 (what vtkDICOMImageReader took as the z spacing), positions 3 apart
    write_series(tmp_path / "s", DCM_VALUES, DCM_SPACING, (1.0, 2.0, 3.0), step=3.0)
    volume = load_volume(tmp_path / "s")
    assert volume.spacing == pytest.approx((0.5, 0.75, 3.0))
    assert volume.origin == pytest.approx((1.0, 2.0, 3.0))
    (tmp_path / "s" / "slice002.dcm").unlink()
    with pytest.warns(UserWarning, match=r"the slice positions are 3 to 6 apart \(a missing slice\?\)"):
        load_volume(tmp_path / "s")


def test_dicom_without_positions_orders_by_instance_number(tmp_path):
    paths = series(tmp_path)
    for path in paths:
        edit(path, (0x20, 0x32), b"")
    paths[0].rename(tmp_path / "series" / "zz.dcm")  # file order no longer the slice order
    with pytest.warns(UserWarning, match="no ImagePositionPatient; ordered them by InstanceNumber, 2 apart"):
        volume = load_volume(tmp_path / "series")
    np.testing.assert_array_equal(volume.values, DCM_VALUES)
    edit(paths[1], (0x20, 0x32), b"0\\0\\0 ")
    fails(tmp_path / "series", "has no ImagePositionPatient, while slice001.dcm has one")


def test_dicom_two_series_in_one_folder(tmp_path):
    series(tmp_path)
    other = write_series(tmp_path / "other", DCM_VALUES[:2], DCM_SPACING, (0.0, 0.0, 50.0))
    for k, path in enumerate(other):
        edit(path, (0x20, 0x0E), b"1.2.3.4.5.6\0")
        path.rename(tmp_path / "series" / f"other{k}.dcm")
    fails(tmp_path / "series", "holds 2 DICOM series", "name one slice file of the series to read")
    assert load_volume(tmp_path / "series" / "slice001.dcm").values.shape == (4, 5, 7)
    assert load_volume(tmp_path / "series" / "other1.dcm").values.shape == (2, 5, 7)


def test_dicom_files_without_an_image_are_skipped(tmp_path):
    series(tmp_path)
    meta = (
        element(2, 1, "OB", b"\0\1")
        + element(2, 2, "UI", "1.2.840.10008.1.3.10")
        + element(2, 0x10, "UI", "1.2.840.10008.1.2.1")
    )
    dicomdir = b"\0" * 128 + b"DICM" + element(2, 0, "UL", len(meta).to_bytes(4, "little")) + meta
    (tmp_path / "series" / "DICOMDIR").write_bytes(dicomdir + element(0x10, 0x10, "PN", "Someone"))
    volume = load_volume(tmp_path / "series")
    np.testing.assert_array_equal(volume.values, DCM_VALUES)
    assert any("skipped 1 DICOM file(s) that hold no image (DICOMDIR)" in n for n in volume.notes)


def test_dicom_slices_differing_in_format(tmp_path):
    paths = series(tmp_path)
    edit(paths[3], (0x28, 0x103), US(0))
    fails(
        tmp_path / "series",
        "the slices differ in pixel format: slice000.dcm is 16-bit signed, slice003.dcm is 16-bit unsigned",
    )
    edit(paths[3], (0x28, 0x103), US(1))
    edit(paths[3], (0x28, 0x30), b"1\\1 ")
    fails(tmp_path / "series", "the slices differ in PixelSpacing")
    edit(paths[3], (0x28, 0x30), b"0.75\\0.5 ")
    edit(paths[3], (0x20, 0x37), b"0\\1\\0\\1\\0\\0 ")
    fails(tmp_path / "series", "the slices are not parallel")


# ----------------------------------------------------------------------------------------- NIfTI

import gzip  # noqa: E402
import struct  # noqa: E402

from benchmarks.fuzz.seeds import seeds  # noqa: E402


def nifti(tmp_path: Path, suffix: str = ".nii", **fields: tuple[int, str, float]) -> Path:
    """The fuzz seed's NIfTI-1 file with `fields` (name=(offset, format, value)) set."""
    seed = next(s for s in seeds() if s.name == "nii")
    data = bytearray(seed.files["v.nii"])
    for offset, fmt, value in fields.values():
        struct.pack_into(fmt, data, offset, value)
    path = tmp_path / f"v{suffix}"
    path.write_bytes(gzip.compress(bytes(data), mtime=0) if suffix == ".nii.gz" else bytes(data))
    return path


NAN, INF = float("nan"), float("inf")


@pytest.mark.parametrize("suffix", [".nii", ".nii.gz"])
@pytest.mark.parametrize("fields, problem", [
    ({"vox_offset": (108, "<f", NAN)}, "NIfTI vox_offset nan must be a whole number of bytes"),  # was a ValueError
    ({"vox_offset": (108, "<f", INF)}, "NIfTI vox_offset inf must be a whole number of bytes"),  # was an OverflowError
    ({"vox_offset": (108, "<f", 0.0)}, "NIfTI vox_offset 0 lies inside the header"),
    ({"vox_offset": (108, "<f", 100.0)}, "NIfTI vox_offset 100 lies inside the header"),
    ({"vox_offset": (108, "<f", 353.5)}, "NIfTI vox_offset 353.5 must be a whole number of bytes"),
    ({"bitpix": (72, "<h", 7)}, "NIfTI bitpix 7 does not match datatype 4 (int16, 16 bits per voxel)"),
    ({"bitpix": (72, "<h", 64)}, "NIfTI bitpix 64 does not match datatype 4"),
    ({"pixdim1": (80, "<f", 0.0)}, "NIfTI pixdim[1] is 0"),
    ({"pixdim3": (88, "<f", NAN)}, "NIfTI header field pixdim[3] is nan"),
    ({"sform_code": (254, "<h", 1), "srow_x0": (280, "<f", NAN)}, "NIfTI header field srow_x[0] is nan"),
    ({"srow_z3": (324, "<f", INF)}, "NIfTI header field srow_z[3] is inf"),
    ({"qoffset_x": (268, "<f", NAN)}, "NIfTI header field qoffset_x is nan"),
    ({"scl_slope": (112, "<f", INF)}, "NIfTI header field scl_slope is inf"),
    ({"magic": (344, "4s", b"ni1\0")}, "NIfTI magic 'ni1' says the data is in a separate .img file"),
    ({"magic": (344, "4s", b"abc\0")}, "not a NIfTI-1 file: magic 'abc?' is not 'n+1'"),
])  # fmt: skip
def test_nifti_header_field_refused(tmp_path, suffix, fields, problem):
    fails(nifti(tmp_path, suffix, **fields), problem)


def test_nifti_gz_cut_or_extended_is_refused(tmp_path):
    path = nifti(tmp_path, ".nii.gz")
    data = path.read_bytes()
    path.write_bytes(data[: int(len(data) * 0.99)])
    fails(path, "truncated: its gzip stream ends before its end marker")
    path.write_bytes(data + b"trailing garbage")
    fails(path, "corrupt: bytes that are not gzip data follow its gzip stream")
    path.write_bytes(data + data)  # two gzip members: one stream, read whole
    assert load_volume(path).values.shape == (6, 7, 8)


def test_nifti_value_scaling_edges(tmp_path):
    plain = load_volume(nifti(tmp_path)).values
    # scl_slope 0 means "no scaling": the intercept is not applied either
    volume = load_volume(nifti(tmp_path, slope=(112, "<f", 0.0), inter=(116, "<f", 5.0)))
    np.testing.assert_array_equal(volume.values, plain)
    # a scaling past float32's range is applied in float64, not overflowed to inf
    volume = load_volume(nifti(tmp_path, slope=(112, "<f", 1e38)))
    assert volume.values.dtype == np.float64
    np.testing.assert_array_equal(volume.values, plain.astype(np.float64) * np.float64(np.float32(1e38)))


# ------------------------------------------------------------------------------ MetaImage flags


@pytest.mark.parametrize("value", ["1e308", "yes", "1", ""])
def test_metaimage_true_false_fields_are_words(tmp_path, value):
    """MetaIO reads any word starting with T, t or 1 as true; volren would read '1e308' as false
    and check the wrong size, so only True and False are accepted."""
    data = grid_values().astype("<i2").tobytes()
    (tmp_path / "v.raw").write_bytes(data)
    header = (
        "NDims = 3\nDimSize = 8 7 6\nElementType = MET_SHORT\nCompressedData = {}\nElementDataFile = v.raw\n"
    )
    (tmp_path / "v.mhd").write_text(header.format(value))
    fails(tmp_path / "v.mhd", "CompressedData", "must be True or False")
    (tmp_path / "ok.mhd").write_text(header.format("False"))
    assert load_volume(tmp_path / "ok.mhd").values.shape == (6, 7, 8)


def test_a_warning_repeated_in_the_reading_child_comes_back_once(recwarn):
    from volren.io.isolation import run_isolated

    run_isolated("x", _warn_three_times)
    assert [str(w.message) for w in recwarn.list if "same note" in str(w.message)] == ["same note"]


def _warn_three_times() -> None:
    import warnings

    from volren.errors import VolrenWarning

    for _ in range(3):
        warnings.warn("same note", VolrenWarning, stacklevel=1)


# ------------------------------------------------------------------------------------------ NRRD


@pytest.mark.parametrize("detached", [False, True])
def test_nrrd_ascii_data_cut_short_is_refused(tmp_path, detached):
    """vtkNrrdReader fills missing ASCII numbers with zeros and reports success."""
    from benchmarks.fuzz.seeds import SHAPE, nrrd_header

    text = " ".join(str(v) for v in grid_values().reshape(-1)).encode()
    count = int(np.prod(SHAPE))
    if detached:
        (tmp_path / "v.nhdr").write_text(nrrd_header("ascii", "v.txt"))
        (tmp_path / "v.txt").write_bytes(text[: len(text) // 2])
        path = tmp_path / "v.nhdr"
    else:
        path = tmp_path / "v.nrrd"
        path.write_bytes((nrrd_header("ascii") + "\n").encode() + text[: len(text) // 2])
    fails(path, "truncated: its ASCII data has", f"the sizes declare {count:,}")


def test_nrrd_ascii_reads_as_its_raw_twin(tmp_path):
    """vtkNrrdReader returns unfilled memory for ASCII data: volren parses it, same geometry."""
    from benchmarks.fuzz.seeds import nrrd_header

    text = " ".join(str(v) for v in grid_values().reshape(-1)).encode()
    (tmp_path / "text.nrrd").write_bytes((nrrd_header("ascii") + "\n").encode() + text + b"\n")
    (tmp_path / "raw.nrrd").write_bytes(
        (nrrd_header() + "\n").encode() + grid_values().astype("<i2").tobytes()
    )
    text_volume, raw_volume = load_volume(tmp_path / "text.nrrd"), load_volume(tmp_path / "raw.nrrd")
    assert np.array_equal(text_volume.values, raw_volume.values) and text_volume.values.dtype == np.int16
    assert text_volume.spacing == raw_volume.spacing == SEED_SPACING
    assert text_volume.origin == raw_volume.origin == (1.0, -2.0, 0.5)


@pytest.mark.parametrize("data, problem", [
    (b"1 2 3 4 5 6 7 8 9", "more than the 8"),
    (b"1 2 3 4 5 6 7 1.5", "ASCII number 8 (1.5) is not a short"),
    (b"1 2 3 4 5 6 7 40000", "ASCII number 8 (40000) is not a short"),
    (b"1 2 3 4 5 6 7 x", "a word that is not a number"),
])  # fmt: skip
def test_nrrd_ascii_numbers_must_fit_the_type(tmp_path, data, problem):
    head = b"NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 2\nencoding: ascii\n\n"
    (tmp_path / "v.nrrd").write_bytes(head + data)
    fails(tmp_path / "v.nrrd", problem)
    (tmp_path / "ok.nrrd").write_bytes(head + b"1 2\n3 4\n5 6\n7 -8\n")
    assert load_volume(tmp_path / "ok.nrrd").values.tolist() == [[[1, 2], [3, 4]], [[5, 6], [7, -8]]]


# ------------------------------------------------------------------------------------- isolation


def test_the_reading_child_is_forked_beside_numpys_blas_threads():
    """numpy's OpenBLAS pool, running since import, is fork-safe: a fresh process reads by fork
    (a server cost the CLI 0.47 s a command); a thread started later makes it use the server."""
    import subprocess
    import sys

    code = (
        "import threading, time\n"
        "from volren.io import isolation\n"
        "print(isolation._how_to_read())\n"
        "threading.Thread(target=time.sleep, args=(1,), daemon=True).start()\n"
        "print(isolation._how_to_read())\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["fork", "server"], out


def test_arrays_come_back_mapped_writable_and_private():
    from volren.io.isolation import run_isolated

    values = np.arange(300_000, dtype=np.float64)
    first, second = run_isolated("a", np.copy, values), run_isolated("b", np.copy, values)
    first[0] = -1.0
    assert second[0] == 0.0 and np.array_equal(first[1:], values[1:])
