"""Small volumes written in every supported format come back with the same values and geometry."""

from __future__ import annotations

import gzip
import struct
from pathlib import Path

import numpy as np
import pytest
import pyvista as pv
import vtk

from volren.errors import VolrenError, VolrenWarning
from volren.io import from_pyvista, load_volume
from volren.model.volume import TetVolume, UniformVolume
from volren.testing.dicom_series import write_series

SPACING = (0.5, 0.75, 2.0)
ORIGIN = (10.0, -20.0, 30.0)


def image(values: np.ndarray, spacing=SPACING, origin=ORIGIN, name: str = "s") -> pv.ImageData:
    nz, ny, nx = values.shape
    img = pv.ImageData(dimensions=(nx, ny, nz), spacing=spacing, origin=origin)
    img.point_data[name] = values.ravel()  # x fastest, as values[k, j, i] is laid out in memory
    return img


def vtk_write(writer, img: pv.ImageData, path: Path, **calls: tuple) -> None:
    """Write with a VTK writer after calling its setters, e.g. SetCompression=(False,)."""
    writer.SetInputData(img)
    writer.SetFileName(str(path))
    for method, args in calls.items():
        getattr(writer, method)(*args)
    writer.Write()


def nrrd_header(
    values: np.ndarray, encoding: str = "raw", data_file: str | None = None, endian="little"
) -> bytes:
    nz, ny, nx = values.shape
    kind = {np.dtype(np.int16): "short", np.dtype(np.float32): "float", np.dtype(np.uint8): "uchar"}[
        values.dtype
    ]
    sx, sy, sz = SPACING
    lines = [
        "NRRD0004", "# written by volren's tests", f"type: {kind}", "dimension: 3", f"sizes: {nx} {ny} {nz}",
        f"space directions: ({sx},0,0) (0,{sy},0) (0,0,{sz})", "space origin: ({},{},{})".format(*ORIGIN),
        f"endian: {endian}", f"encoding: {encoding}", "kinds: domain domain domain",
    ]  # fmt: skip
    if data_file:
        lines.append(f"data file: {data_file}")
    return ("\n".join(lines) + "\n\n").encode()


# Each writer puts `values` into a file in tmp_path and returns its path.
def _vti_zlib(v, tmp):
    image(v).save(tmp / "v.vti", binary=True)
    return tmp / "v.vti"


def _vti_raw(v, tmp):
    image(v).save(tmp / "v.vti", binary=True, compression=None)
    return tmp / "v.vti"


def _vti_ascii(v, tmp):
    vtk_write(vtk.vtkXMLImageDataWriter(), image(v), tmp / "v.vti", SetDataModeToAscii=())
    return tmp / "v.vti"


def _vtk_binary(v, tmp):
    image(v).save(tmp / "v.vtk", binary=True)
    return tmp / "v.vtk"


def _vtk_ascii(v, tmp):
    image(v).save(tmp / "v.vtk", binary=False)
    return tmp / "v.vtk"


def _mhd(v, tmp):
    vtk_write(vtk.vtkMetaImageWriter(), image(v), tmp / "v.mhd", SetCompression=(False,))
    return tmp / "v.mhd"


def _mha(v, tmp):
    vtk_write(vtk.vtkMetaImageWriter(), image(v), tmp / "v.mha", SetCompression=(True,))
    return tmp / "v.mha"


def _nii(v, tmp):
    image(v).save(tmp / "v.nii")
    return tmp / "v.nii"


def _nii_gz(v, tmp):
    image(v).save(tmp / "v.nii.gz")
    return tmp / "v.nii.gz"


def _nrrd(v, tmp):
    (tmp / "v.nrrd").write_bytes(nrrd_header(v) + v.astype(v.dtype.newbyteorder("<")).tobytes())
    return tmp / "v.nrrd"


def _nrrd_gzip_big_endian(v, tmp):
    data = gzip.compress(v.astype(v.dtype.newbyteorder(">")).tobytes())
    (tmp / "v.nrrd").write_bytes(nrrd_header(v, "gzip", endian="big") + data)
    return tmp / "v.nrrd"


def _nhdr(v, tmp):
    (tmp / "v.nhdr").write_bytes(nrrd_header(v, data_file="v.data"))
    (tmp / "v.data").write_bytes(v.tobytes())
    return tmp / "v.nhdr"


WRITERS = {
    "vti-zlib": _vti_zlib, "vti-raw": _vti_raw, "vti-ascii": _vti_ascii, "vtk-binary": _vtk_binary,
    "vtk-ascii": _vtk_ascii, "mhd": _mhd, "mha-compressed": _mha, "nii": _nii, "nii.gz": _nii_gz,
    "nrrd": _nrrd, "nrrd-gzip-big-endian": _nrrd_gzip_big_endian, "nhdr": _nhdr,
}  # fmt: skip


@pytest.mark.parametrize("dtype", [np.int16, np.float32])
@pytest.mark.parametrize("fmt", sorted(WRITERS))
def test_uniform_round_trip(fmt, dtype, tmp_path, values_int16, values_float32):
    values = values_int16 if dtype == np.int16 else values_float32
    path = WRITERS[fmt](values, tmp_path)
    volume = load_volume(path)
    assert isinstance(volume, UniformVolume)
    assert volume.name == path.name
    assert volume.values.dtype == dtype
    np.testing.assert_array_equal(volume.values, values)
    assert volume.spacing == pytest.approx(SPACING, rel=1e-6)  # NIfTI stores float32
    assert volume.origin == pytest.approx(ORIGIN, rel=1e-6)


@pytest.mark.parametrize("byte_order", ["little", "big"])
def test_raw_round_trip(byte_order, tmp_path, values_int16):
    path = tmp_path / "v.raw"
    values_int16.astype(values_int16.dtype.newbyteorder("<" if byte_order == "little" else ">")).tofile(path)
    volume = load_volume(
        path, shape=(7, 5, 4), dtype="int16", byte_order=byte_order, spacing=SPACING, origin=ORIGIN
    )
    assert volume.values.dtype == np.int16 and volume.values.dtype.isnative
    np.testing.assert_array_equal(volume.values, values_int16)
    assert (volume.spacing, volume.origin) == (SPACING, ORIGIN)


def test_raw_with_header_and_any_suffix(tmp_path, values_float32):
    path = tmp_path / "volume.bin"
    path.write_bytes(b"HEADER!!" + values_float32.tobytes())
    volume = load_volume(path, shape=(7, 5, 4), dtype=np.float32, header_bytes=8)
    np.testing.assert_array_equal(volume.values, values_float32)


def test_raw_uint8_needs_no_dtype(tmp_path):
    values = np.arange(60, dtype=np.uint8).reshape(3, 4, 5)
    values.tofile(tmp_path / "v.raw")
    np.testing.assert_array_equal(load_volume(tmp_path / "v.raw", shape=(5, 4, 3)).values, values)


def test_dicom_series_round_trip(tmp_path, values_int16):
    write_series(tmp_path / "series", values_int16, SPACING, ORIGIN)
    (tmp_path / "series" / "README.txt").write_text("not a slice")
    for path in (tmp_path / "series", tmp_path / "series" / "slice002.dcm"):  # the folder, or one file in it
        volume = load_volume(path)
        assert volume.name == "series"
        assert volume.values.dtype == np.int16
        np.testing.assert_array_equal(volume.values, values_int16)  # patient order, row 0 first
        assert volume.spacing == pytest.approx(SPACING)
        assert volume.origin == pytest.approx(ORIGIN)


def test_dicom_slices_written_in_decreasing_position(tmp_path, values_int16):
    # slice k at z = 30 - 2k: patient order puts the last slice (lowest z) first
    write_series(tmp_path / "series", values_int16, SPACING, ORIGIN, step=-SPACING[2])
    volume = load_volume(tmp_path / "series")
    np.testing.assert_array_equal(volume.values, values_int16[::-1])
    assert volume.origin == pytest.approx((ORIGIN[0], ORIGIN[1], ORIGIN[2] - 3 * SPACING[2]))


@pytest.mark.parametrize("suffix", [".vtu", ".vtk"])
@pytest.mark.parametrize("binary", [True, False])
def test_tet_round_trip(suffix, binary, tmp_path):
    grid = (
        pv.ImageData(dimensions=(4, 3, 3), spacing=(1.0, 0.5, 2.0)).cast_to_unstructured_grid().triangulate()
    )
    grid.point_data["f"] = np.round(np.linspace(-1, 1, grid.n_points), 3).astype(
        np.float32
    )  # ASCII keeps 6 digits
    grid.save(tmp_path / f"t{suffix}", binary=binary)
    volume = load_volume(tmp_path / f"t{suffix}")  # no warning: nothing to repair
    assert isinstance(volume, TetVolume)
    np.testing.assert_array_equal(volume.points, grid.points)
    np.testing.assert_array_equal(volume.values, grid.point_data["f"])
    assert len(volume.tets) == grid.n_cells


# ------------------------------------------------------------------------ geometry and arrays


def test_extent_not_starting_at_zero_moves_the_origin(tmp_path, values_int16):
    img = pv.ImageData(dimensions=(7, 5, 4), spacing=SPACING, origin=(0, 0, 0), offset=(2, 3, 4))
    img.point_data["s"] = values_int16.ravel()
    img.save(tmp_path / "v.vti")
    volume = load_volume(tmp_path / "v.vti")
    assert volume.origin == pytest.approx((2 * 0.5, 3 * 0.75, 4 * 2.0))
    np.testing.assert_array_equal(volume.values, values_int16)


def test_direction_matrix_is_ignored_with_a_warning(tmp_path, values_int16):
    img = image(values_int16)
    img.direction_matrix = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
    img.save(tmp_path / "rotated.vti")
    with pytest.warns(VolrenWarning, match=r"rotated.vti: ignored the direction matrix \[\[0.0, -1.0, 0.0\]"):
        volume = load_volume(tmp_path / "rotated.vti")
    assert "ignored the direction matrix" in volume.notes[0]
    assert volume.origin == pytest.approx(ORIGIN)


def test_nrrd_space_directions_rotation_is_reported(tmp_path, values_int16):
    header = nrrd_header(values_int16).replace(b"(0.5,0,0) (0,0.75,0)", b"(0,0.5,0) (-0.75,0,0)")
    (tmp_path / "r.nrrd").write_bytes(header + values_int16.tobytes())
    with pytest.warns(VolrenWarning, match="r.nrrd: ignored the direction matrix"):
        volume = load_volume(tmp_path / "r.nrrd")
    assert volume.spacing == pytest.approx(SPACING)


@pytest.mark.parametrize("nx", [7, 12])  # VTK takes a first axis of <= 9 samples for vector components
@pytest.mark.parametrize("encoding", ["raw", "gzip"])
def test_nrrd_left_handed_space_keeps_file_order(tmp_path, nx, encoding):
    values = np.arange(nx * 5 * 4, dtype=np.int16).reshape(4, 5, nx)
    data = values.tobytes() if encoding == "raw" else gzip.compress(values.tobytes())
    header = f"NRRD0004\ntype: short\ndimension: 3\nsizes: {nx} 5 4\nspace: left-anterior-superior\n"
    header += f"space directions: (1,0,0) (0,1,0) (0,0,1)\nendian: little\nencoding: {encoding}\n\n"
    (tmp_path / "las.nrrd").write_bytes(header.encode() + data)
    if encoding == "raw":  # VTK's reader mirrors these rows (volren undoes it): say that VTK's tools differ
        axis = "y" if nx > 9 else "z"
        note = f"las.nrrd: drawn in the file's own order; VTK, ParaView and PyVista mirror its left-handed space " \
               f"'left-anterior-superior' in {axis}"  # fmt: skip
        with pytest.warns(VolrenWarning) as record:
            volume = load_volume(tmp_path / "las.nrrd")
        assert [str(w.message) for w in record] == [note]
    else:
        volume = load_volume(tmp_path / "las.nrrd")
    np.testing.assert_array_equal(volume.values, values)


def test_nifti_value_scaling_is_applied(tmp_path, values_int16):
    path = _nii(values_int16, tmp_path)
    header = bytearray(path.read_bytes())
    struct.pack_into("<ff", header, 112, 2.0, -5.0)  # scl_slope, scl_inter
    path.write_bytes(bytes(header))
    volume = load_volume(path)
    assert volume.values.dtype == np.float32
    np.testing.assert_array_equal(volume.values, values_int16 * 2.0 - 5.0)
    assert any("scaling" in note for note in volume.notes)


def test_cell_data_only_is_moved_to_points(tmp_path):
    img = pv.ImageData(dimensions=(4, 3, 3))
    img.cell_data["c"] = np.arange(img.n_cells, dtype=np.float32)
    img.save(tmp_path / "cells.vti")
    with pytest.warns(VolrenWarning, match="cells.vti: array 'c' is cell data; averaged it onto the points"):
        volume = load_volume(tmp_path / "cells.vti")
    assert volume.dimensions == (4, 3, 3)
    assert volume.value_range == (0.0, 11.0)  # corner points take their one cell's value
    assert volume.values[0, 0, 0] == 0.0 and volume.values[0, 0, 1] == 0.5  # mean of cells 0 and 1


def test_named_and_default_arrays(tmp_path, values_int16):
    img = image(values_int16, name="first")
    img.point_data["second"] = (values_int16 * 2).ravel()
    img.point_data["vectors"] = np.zeros((img.n_points, 3), np.float32)
    img.set_active_scalars("second")
    img.save(tmp_path / "many.vti")
    np.testing.assert_array_equal(load_volume(tmp_path / "many.vti").values, values_int16 * 2)  # active
    np.testing.assert_array_equal(load_volume(tmp_path / "many.vti", "first").values, values_int16)
    with pytest.raises(
        VolrenError,
        match=r"many.vti: no array named 'nope'; available: 'first', 'second', 'vectors:magnitude', "
        "'vectors:x', 'vectors:y', 'vectors:z'",
    ):
        load_volume(tmp_path / "many.vti", "nope")


def test_a_vector_array_gives_its_magnitude_or_a_component(tmp_path, values_int16):
    """Issue 23: choosing a vector's component or magnitude, as in ParaView (magnitude by default)."""
    img = image(values_int16, name="first")
    rng = np.random.default_rng(3)
    vectors = rng.normal(size=(img.n_points, 3)).astype(np.float32)
    img.point_data["velocity"] = vectors
    img.cell_data["flux"] = rng.normal(size=(img.n_cells, 2))
    img.save(tmp_path / "vec.vti")
    path = tmp_path / "vec.vti"
    shape = values_int16.shape
    magnitude = load_volume(path, "velocity")
    np.testing.assert_allclose(magnitude.values, np.linalg.norm(vectors, axis=1).reshape(shape), rtol=1e-6)
    assert magnitude.values.dtype == np.float32 and magnitude.scalars == "velocity:magnitude"
    assert any("'velocity' has 3 components; showing its magnitude" in note for note in magnitude.notes)
    assert load_volume(path, "velocity:magnitude").scalars == "velocity:magnitude"
    for component, index in (("x", 0), ("y", 1), ("Z", 2), ("1", 1)):
        part = load_volume(path, f"velocity:{component}")
        np.testing.assert_array_equal(part.values, vectors[:, index].reshape(shape))
        assert part.scalars == f"velocity:{'xyz'[index]}" and part.notes == ()
    assert magnitude.arrays == ("first", "velocity:magnitude", "velocity:x", "velocity:y", "velocity:z",
                                "flux:magnitude", "flux:x", "flux:y")  # fmt: skip
    assert load_volume(path).scalars == "first" and load_volume(path, "first:0").scalars == "first"
    with pytest.warns(VolrenWarning, match="array 'flux' is cell data"):
        assert load_volume(path, "flux:y").scalars == "flux:y"
    with pytest.raises(VolrenError, match=r"vec.vti: array 'velocity' has 3 components; no component 'w' \(choose "
                       r"velocity:magnitude, velocity:x, velocity:y, velocity:z\)"):  # fmt: skip
        load_volume(path, "velocity:w")
    with pytest.raises(VolrenError, match="array 'first' has one component; there is no component 'y'"):
        load_volume(path, "first:y")


def test_nan_values_load_with_one_warning(tmp_path, values_float32):
    values = values_float32.copy()
    values[0, 0, :3] = np.nan
    values[1, 1, 1] = np.inf
    image(values).save(tmp_path / "nan.vti")
    with pytest.warns(
        VolrenWarning, match="nan.vti: 4 values are NaN or Inf; they render transparent"
    ) as record:
        volume = load_volume(tmp_path / "nan.vti")
    assert len(record) == 1
    assert volume.nonfinite_count == 4


def test_negative_spacing_is_flipped(values_int16):
    img = vtk.vtkImageData()  # pyvista refuses negative spacing; VTK allows it
    img.SetDimensions(7, 5, 4)
    img.SetSpacing(0.5, -0.75, 2.0)
    img.SetOrigin(0, 3, 0)
    img.GetPointData().SetScalars(pv.convert_array(values_int16.ravel(), name="s"))
    volume = from_pyvista(img, name="flipped")
    assert volume.spacing == (0.5, 0.75, 2.0)
    assert volume.origin == pytest.approx((0, 0, 0))
    np.testing.assert_array_equal(volume.values, values_int16[:, ::-1, :])


# ------------------------------------------------------------------------------- from_pyvista


def test_from_pyvista_image_and_grids(values_int16):
    uniform = from_pyvista(image(values_int16), name="mem")
    assert isinstance(uniform, UniformVolume) and uniform.name == "mem"
    np.testing.assert_array_equal(uniform.values, values_int16)
    # a raw VTK object works too
    assert from_pyvista(vtk.vtkImageData.SafeDownCast(image(values_int16))).dimensions == (7, 5, 4)
    structured = pv.StructuredGrid(
        *np.meshgrid(np.arange(3.0), np.arange(3.0), np.arange(2.0), indexing="ij")
    )
    structured.point_data["p"] = np.arange(structured.n_points, dtype=np.float32)
    with pytest.warns(VolrenWarning, match="tetrahedralized 4 hexahedra"):
        mesh = from_pyvista(structured, name="sg")
    assert isinstance(mesh, TetVolume)
    assert mesh.tets.shape[1] == 4


def test_from_pyvista_refuses_what_is_not_a_volume():
    with pytest.raises(VolrenError, match="dataset: expected a pyvista or VTK dataset, got str"):
        from_pyvista("bonsai.vti")
    with pytest.raises(
        VolrenError, match=r"sphere: no 3D cells to render \(the grid holds [\d,]+ triangles\)"
    ):
        from_pyvista(_sphere_with_scalars(), name="sphere")


def _sphere_with_scalars() -> pv.PolyData:
    sphere = pv.Sphere()
    sphere.point_data["s"] = np.arange(sphere.n_points, dtype=np.float32)
    return sphere
