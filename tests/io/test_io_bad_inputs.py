"""Every bad input is one VolrenError line naming the file and the problem; nothing crashes or hangs."""

from __future__ import annotations

import gzip
import os
import struct
import subprocess
import sys
import textwrap
import zlib
from pathlib import Path

import numpy as np
import pytest
import pyvista as pv

from volren.errors import VolrenError
from volren.io import load_volume
from volren.testing.dicom_series import write_series

SPACING = (0.5, 0.75, 2.0)
ORIGIN = (0.0, 0.0, 0.0)


def fails(path: Path | str, *fragments: str, **kwargs) -> str:
    """Load `path`, expect a one-line VolrenError that names it and contains every fragment."""
    with pytest.raises(VolrenError) as info:
        load_volume(path, **kwargs)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{path}:") or message.startswith(f"{Path(path).name}:"), message
    for fragment in fragments:
        assert fragment in message, message
    return message


def cut(src: Path, dst: Path, n: int) -> Path:
    dst.write_bytes(src.read_bytes()[:n])
    return dst


@pytest.fixture
def small(tmp_path) -> pv.ImageData:
    img = pv.ImageData(dimensions=(16, 12, 10), spacing=SPACING)
    img.point_data["s"] = np.arange(img.n_points, dtype=np.float32)
    return img


# ------------------------------------------------------------------------------ the path itself


def test_missing_empty_unknown(tmp_path):
    fails(tmp_path / "nope.vti", "no such file or folder")
    for suffix in (".vti", ".vtk", ".vtu", ".nrrd", ".mha", ".nii", ".nii.gz", ".slc", ".dcm"):
        (tmp_path / f"empty{suffix}").touch()
        fails(tmp_path / f"empty{suffix}", "empty file (0 bytes)")
    (tmp_path / "volume.xyz").write_text("data")
    message = fails(tmp_path / "volume.xyz", "unknown volume format '.xyz'; volren reads .vti, .vtk, .vtu")
    assert ".nii.gz" in message and "DICOM folder" in message and ".raw" in message


def test_folder_without_dicom(tmp_path):
    (tmp_path / "notes.txt").write_text("no images here")
    fails(tmp_path, "holds no DICOM images")


# ----------------------------------------------------------------------------- garbage contents

GARBAGE = {
    ".vti": "not a VTK XML file",
    ".vtu": "not a VTK XML file",
    ".vtk": "not a legacy VTK file",
    ".nrrd": "not a NRRD file",
    ".nhdr": "not a NRRD file",
    ".mhd": "not a MetaImage header",
    ".mha": "not a MetaImage header",
    ".nii": "not a NIfTI file",
    ".nii.gz": "not a gzip-compressed NIfTI file",
    ".slc": "not an SLC file",
}


@pytest.mark.parametrize("suffix", sorted(GARBAGE))
def test_garbage(suffix, tmp_path):
    path = tmp_path / f"garbage{suffix}"
    path.write_bytes(np.random.default_rng(1).integers(0, 256, 5000, dtype=np.uint8).tobytes())
    fails(path, GARBAGE[suffix])


def test_plausible_garbage(tmp_path):
    (tmp_path / "g.vtk").write_bytes(b"# vtk DataFile Version 3.0\nx\nBINARY\n" + bytes(range(256)) * 4)
    fails(tmp_path / "g.vtk", "not a legacy VTK file: expected a DATASET line")
    (tmp_path / "g.nrrd").write_bytes(b"NRRD0004\nthis is not a field\n\n")
    fails(tmp_path / "g.nrrd", "not a valid NRRD header: line 2 'this is not a field'")
    (tmp_path / "g.vti").write_text('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid"></VTKFile>\n')
    fails(tmp_path / "g.vti", "holds VTK XML data of type 'UnstructuredGrid', not ImageData")
    poly = pv.Sphere()
    poly.save(tmp_path / "sphere.vtk")
    fails(tmp_path / "sphere.vtk", "legacy VTK DATASET POLYDATA is not a volume")


def test_corrupt_compressed_data(tmp_path, small):
    small.save(tmp_path / "z.vti")
    data = bytearray((tmp_path / "z.vti").read_bytes())
    start = data.index(b">", data.index(b"<DataArray")) + 40  # inside the base64 of the compressed blocks
    data[start : start + 200] = b"A" * 200
    (tmp_path / "z.vti").write_bytes(bytes(data))
    fails(tmp_path / "z.vti", "corrupt")


def test_nrrd_gzip_data_that_is_not_gzip(tmp_path):
    """VTK's reader passes bytes that are not gzip through as they are: raw data under 'encoding:
    gzip' rendered as if the header said raw, and a zlib stream became garbage."""
    values = (np.arange(4 * 5 * 6) % 251).astype(np.uint8).tobytes()
    header = b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 5 6\nencoding: gzip\n"
    (tmp_path / "raw.nrrd").write_bytes(header + b"\n" + values)
    fails(tmp_path / "raw.nrrd", "the header says 'encoding: gzip' but the data is not gzip", "but 00 01")
    (tmp_path / "zlib.nrrd").write_bytes(header + b"\n" + zlib.compress(values))
    fails(
        tmp_path / "zlib.nrrd", "the data is not gzip (it does not start with gzip's bytes 1f 8b but 78 9c)"
    )
    (tmp_path / "d.raw").write_bytes(values)
    (tmp_path / "d.nhdr").write_bytes(header + b"data file: d.raw\n")
    fails(tmp_path / "d.nhdr", "the data in d.raw is not gzip")
    (tmp_path / "gz.nrrd").write_bytes(header + b"\n" + gzip.compress(values))
    assert load_volume(tmp_path / "gz.nrrd").values.tobytes() == values


@pytest.mark.parametrize("mode, compressor", [("Ascii", "None"), ("Binary", "None"), ("Binary", "ZLib"),
                                              ("Appended", "None"), ("Appended", "LZ4")])  # fmt: skip
def test_vti_extent_smaller_than_its_data(tmp_path, mode, compressor):
    """VTK's reader takes the first values that fit the Extent, laid out on its smaller grid."""
    from vtkmodules.vtkIOXML import vtkXMLImageDataWriter

    img = pv.ImageData(dimensions=(5, 4, 3))
    img.point_data["s"] = np.arange(60, dtype=np.int16)
    writer = vtkXMLImageDataWriter()
    writer.SetInputData(img)
    writer.SetFileName(str(tmp_path / "v.vti"))
    getattr(writer, f"SetDataModeTo{mode}")()
    getattr(writer, f"SetCompressorTypeTo{compressor}")()
    writer.Write()
    assert load_volume(tmp_path / "v.vti").values.shape == (3, 4, 5)
    text = (tmp_path / "v.vti").read_bytes().replace(b'Extent="0 4 0 3 0 2"', b'Extent="0 4 0 2 0 2"')
    (tmp_path / "v.vti").write_bytes(text)
    fails(
        tmp_path / "v.vti",
        "data array 's' holds 60 values, more than the 45 points x 1 of its piece's Extent",
    )


# ------------------------------------------------------------------------------------ truncation


@pytest.mark.parametrize("fraction", [0.3, 0.6, 0.999])
@pytest.mark.parametrize(
    "folder, name",
    [("uniform", "bonsai.vti"), ("uniform", "ironProt.vtk"), ("uniform", "neghip.slc"), ("tets", "spx.vtk"),
     ("tets", "post_small_tets.vtk"), ("tets", "bluntfin_tets.vtu")],
)  # fmt: skip
def test_truncated_real_files(shared_data, tmp_path, folder, name, fraction):
    src = shared_data / folder / name
    path = cut(src, tmp_path / name, int(src.stat().st_size * fraction))
    fails(path, "truncated")


def test_truncated_metaimage_data_file(shared_data, tmp_path):
    src = shared_data / "uniform"
    (tmp_path / "HeadMRVolume.mhd").write_bytes((src / "HeadMRVolume.mhd").read_bytes())
    cut(src / "HeadMRVolume.raw", tmp_path / "HeadMRVolume.raw", 100_000)
    fails(
        tmp_path / "HeadMRVolume.mhd",
        "truncated (or wrong dimensions): the header declares 48x62x42 uchar = 124,992 bytes of data "
        "but only 100,000 bytes follow in HeadMRVolume.raw",
    )
    (tmp_path / "HeadMRVolume.raw").unlink()
    fails(tmp_path / "HeadMRVolume.mhd", "the data file 'HeadMRVolume.raw' named in the header is missing")


def _write_all(img: pv.ImageData, tmp: Path) -> dict[str, Path]:
    """The small image in every format with uncompressed data, for cutting."""
    import vtk

    out = {}
    for suffix in (".vti", ".vtk", ".nii"):
        img.save(tmp / f"w{suffix}", **({"compression": None} if suffix == ".vti" else {}))
        out[suffix] = tmp / f"w{suffix}"
    writer = vtk.vtkMetaImageWriter()
    writer.SetInputData(img)
    writer.SetFileName(str(tmp / "w.mha"))
    writer.SetCompression(False)
    writer.Write()
    out[".mha"] = tmp / "w.mha"
    values = np.asarray(img.point_data["s"])
    header = b"NRRD0004\ntype: float\ndimension: 3\nsizes: 16 12 10\nencoding: raw\nendian: little\n\n"
    (tmp / "w.nrrd").write_bytes(header + values.tobytes())
    out[".nrrd"] = tmp / "w.nrrd"
    img.save(tmp / "w.nii.gz")
    out[".nii.gz"] = tmp / "w.nii.gz"
    return out


@pytest.mark.parametrize("fraction", [0.5, 0.9, 0.98])  # 0.98 still cuts data, not just trailing text
def test_truncated_formats(tmp_path, small, fraction):
    for suffix, path in _write_all(small, tmp_path).items():
        short = cut(path, tmp_path / f"short{suffix}", int(path.stat().st_size * fraction))
        fails(short, "truncated")


def test_nrrd_header_cut_short(tmp_path, small):
    path = _write_all(small, tmp_path)[".nrrd"]
    for n in (12, 40):  # inside the header: VTK's reader would hang on these
        fails(
            cut(path, tmp_path / f"h{n}.nrrd", n), "truncated: the NRRD header's last line has no line break"
        )
    (tmp_path / "d.nhdr").write_text("NRRD0004\ntype: float\ndimension: 3\nsizes: 16 12 10\nencoding: raw")
    fails(tmp_path / "d.nhdr", "no line break")


def test_truncated_dicom_slice(tmp_path):
    values = np.arange(4 * 5 * 7, dtype=np.int16).reshape(4, 5, 7)
    paths = write_series(tmp_path / "series", values, SPACING, ORIGIN)
    paths[2].write_bytes(paths[2].read_bytes()[:-10])
    fails(
        tmp_path / "series",
        "slice slice002.dcm: truncated: its pixel element declares 70 bytes, the file holds 60",
    )
    write_series(tmp_path / "mixed", values, SPACING, ORIGIN)
    write_series(tmp_path / "other", values[:, :4, :], SPACING, ORIGIN)
    (tmp_path / "other" / "slice000.dcm").rename(tmp_path / "mixed" / "zz.dcm")
    fails(tmp_path / "mixed", "the slices differ in size: slice000.dcm is 7x5", "zz.dcm is 7x4")


# ---------------------------------------------------------------------- sizes and dimensions


def _nifti_header(dims: tuple[int, int, int]) -> bytes:
    header = bytearray(352)
    struct.pack_into("<i", header, 0, 348)
    struct.pack_into("<8h", header, 40, 3, *dims, 1, 1, 1, 1)
    struct.pack_into("<hh", header, 70, 2, 8)  # uint8
    struct.pack_into("<8f", header, 76, 0, 1, 1, 1, 1, 1, 1, 1)
    struct.pack_into("<f", header, 108, 352.0)
    header[344:348] = b"n+1\x00"
    return bytes(header)


HUGE = "100000 100000 100000"
LEGACY = "# vtk DataFile Version 3.0\nx\n"
ABSURD = {
    "huge.mhd": f"NDims = 3\nDimSize = {HUGE}\nElementType = MET_UCHAR\nElementDataFile = huge.raw\n",
    "huge.mha": f"NDims = 3\nDimSize = {HUGE}\nElementType = MET_FLOAT\nElementDataFile = LOCAL\nabc",
    "huge.nrrd": f"NRRD0004\ntype: uchar\ndimension: 3\nsizes: {HUGE}\nencoding: raw\n\nabc",
    "huge.vti": '<VTKFile type="ImageData"><ImageData WholeExtent="0 99999 0 99999 0 99999">'
    '<Piece Extent="0 99999 0 99999 0 99999"><PointData><DataArray type="Float32" Name="a" format="ascii">'
    "1 2 3</DataArray></PointData></Piece></ImageData></VTKFile>",
    "huge_points.vtk": f"{LEGACY}ASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS {HUGE}\nSPACING 1 1 1\n"
    "ORIGIN 0 0 0\nPOINT_DATA 1000000000000000\nSCALARS s float\nLOOKUP_TABLE default\n1 2 3\n",
    "huge_cells.vtk": f"{LEGACY}BINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 100000000000 float\nabc",
    "huge.slc": "11111\n100000 100000 100000 8\n1 1 1\n1 6 0 1\n",
    "huge.nii": _nifti_header((30000, 30000, 30000)) + b"abc",
}


@pytest.mark.parametrize("name", sorted(ABSURD))
def test_absurd_sizes_are_refused_before_reading(name, tmp_path):
    # VTK's readers abort the whole process (std::bad_alloc) on most of these
    content = ABSURD[name]
    (tmp_path / name).write_bytes(content if isinstance(content, bytes) else content.encode())
    fails(tmp_path / name, "too large: the header declares", "more than this machine's")


def test_header_dimensions_larger_than_the_data(tmp_path, small):
    values = np.asarray(small.point_data["s"])
    (tmp_path / "d.raw").write_bytes(values.tobytes())
    (tmp_path / "big.mhd").write_text(
        "NDims = 3\nDimSize = 16 12 11\nElementType = MET_FLOAT\nElementDataFile = d.raw\n"
    )
    fails(
        tmp_path / "big.mhd",
        "truncated (or wrong dimensions): the header declares 16x12x11 float = 8,448 bytes",
    )
    (tmp_path / "big.nhdr").write_text(
        "NRRD0004\ntype: float\ndimension: 3\nsizes: 16 12 11\nencoding: raw\ndata file: d.raw\n"
    )
    fails(
        tmp_path / "big.nhdr",
        "the header declares 16x12x11 float = 8,448 bytes of data but only 7,680 bytes follow in d.raw",
    )
    small.save(tmp_path / "p.vtk", binary=True)
    text = (tmp_path / "p.vtk").read_bytes().replace(b"POINT_DATA 1920", b"POINT_DATA 1900")
    (tmp_path / "p.vtk").write_bytes(text)
    fails(
        tmp_path / "p.vtk",
        "dimensions do not match the data: DIMENSIONS 16x12x10 means 1,920 points but POINT_DATA says 1,900",
    )


def test_raw_sizes(tmp_path):
    (tmp_path / "v.raw").write_bytes(bytes(200))
    fails(tmp_path / "v.raw", "headerless raw data (200 bytes): give shape=(nx, ny, nz) and dtype=")
    (tmp_path / "cube.raw").write_bytes(bytes(2 * 16**3))
    fails(tmp_path / "cube.raw", "headerless raw data of 8,192 bytes: a 16^3 int16 volume? give shape=(16, 16, 16), "
                                 "dtype='int16'")  # fmt: skip
    (tmp_path / "cube.raw").write_bytes(bytes(256**3))
    fails(
        tmp_path / "cube.raw",
        "16,777,216 bytes: a 256^3 uint8 volume (or 128^3 float64)? give shape=(256, 256, 256)",
    )
    for alias, dtype in (
        ("uchar", np.uint8),
        ("MET_SHORT", np.int16),
        ("float", np.float32),
        ("unsigned short", np.uint16),
    ):
        assert (
            load_volume(
                tmp_path / "v.raw", shape=(5, 5, 8 // np.dtype(dtype).itemsize), dtype=alias
            ).values.dtype
            == dtype
        )
    fails(tmp_path / "v.raw", "unknown dtype 'quad'; give one of uint8, int8, uint16, int16, uint32, int32, uint64, int64, "
                              "float32, float64 (or a C, NRRD or MetaImage name", shape=(5, 5, 8), dtype="quad")  # fmt: skip
    fails(
        tmp_path / "v.raw",
        "dimensions do not match the data: shape 10x10x10 of int16 needs 2,000 bytes",
        shape=(10, 10, 10),
        dtype="int16",
    )
    fails(tmp_path / "v.raw", "the file holds 200", shape=(5, 5, 5), dtype="uint8")
    fails(tmp_path / "v.raw", "too large", shape=(100000, 100000, 100000), dtype="float32")
    fails(
        tmp_path / "v.raw",
        "needs dtype= (the file holds 200 bytes for 100 samples, 2 each)",
        shape=(10, 5, 2),
    )
    fails(tmp_path / "v.raw", "unknown dtype 'int17'", shape=(10, 5, 2), dtype="int17")
    fails(
        tmp_path / "v.raw", "byte_order must be one of", shape=(10, 5, 2), dtype="int16", byte_order="middle"
    )
    fails(
        tmp_path / "v.raw",
        "shape must be three whole numbers from 1 to 2,147,483,647",
        shape=(10, 20),
        dtype="int16",
    )
    fails(tmp_path / "v.raw", "shape must be three whole numbers", shape=(10, 20, 1.5), dtype="int16")
    fails(tmp_path / "v.raw", "shape must be three whole numbers", shape=(10, 20, 10**400), dtype="int16")
    with pytest.raises(
        VolrenError, match=r"dtype= describe headerless raw data only; give shape=\(nx, ny, nz\)"
    ):
        load_volume(tmp_path / "v.raw", dtype="int16")
    with pytest.raises(VolrenError, match="spacing=, origin= describe headerless raw data only"):
        load_volume(tmp_path / "v.raw", spacing=(2, 2, 2), origin=(1, 1, 1))


# ------------------------------------------------------------------------------ content problems


def test_no_scalars_and_empty_grids(tmp_path):
    pv.ImageData(dimensions=(4, 4, 4)).save(tmp_path / "bare.vti")
    fails(tmp_path / "bare.vti", "no scalar arrays (neither point nor cell data)")
    img = pv.ImageData(dimensions=(4, 4, 4))
    img.point_data["a"] = np.zeros(64, np.float32)
    img.save(tmp_path / "one.vti")
    fails(tmp_path / "one.vti", "no array named 'b'; available: 'a'", scalars="b")
    pv.UnstructuredGrid().save(tmp_path / "empty.vtu")
    fails(tmp_path / "empty.vtu", "the grid is empty (0 points, 0 cells)")


def test_vtk_stays_quiet(tmp_path, capfd, small):
    """What VTK prints while failing (to its output window or straight to stderr) is caught."""
    for suffix, path in _write_all(small, tmp_path).items():
        cut(path, tmp_path / f"c{suffix}", int(path.stat().st_size * 0.97))
    import vtk

    writer = vtk.vtkMetaImageWriter()  # compressed: the size cannot be checked, MetaIO prints to std::cerr
    writer.SetInputData(small)
    writer.SetFileName(str(tmp_path / "z.mha"))
    writer.SetCompression(True)
    writer.Write()
    cut(tmp_path / "z.mha", tmp_path / "cz.mha", (tmp_path / "z.mha").stat().st_size - 30)
    capfd.readouterr()
    for path in sorted(tmp_path.glob("c*")):
        with pytest.raises(VolrenError):
            load_volume(path)
    out, err = capfd.readouterr()
    assert (out, err) == ("", "")


# ----------------------------------------------------------------------- no crash, no hang


CHILD = textwrap.dedent(
    """
    import sys, warnings
    from volren.errors import VolrenError
    from volren.io import load_volume
    warnings.simplefilter("ignore")
    for path in sys.argv[1:]:
        try:
            load_volume(path)
            print("LOADED", path)
        except VolrenError as exc:
            print("ERROR", exc)
        sys.stdout.flush()
    """
)


def test_truncated_files_never_crash_or_hang(tmp_path, small):
    """Cuts that abort, hang or silently misread VTK's readers, run in a child process."""
    files = []
    for path in _write_all(small, tmp_path).values():
        size = path.stat().st_size
        for n in sorted({1, 10, 60, 120, 400, size // 2, size - 40}):
            files.append(cut(path, tmp_path / f"t{n}_{path.name}", n))
    for name, content in ABSURD.items():
        (tmp_path / name).write_bytes(content if isinstance(content, bytes) else content.encode())
        files.append(tmp_path / name)
    (tmp_path / "huge.raw").write_bytes(b"abc")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    result = subprocess.run(
        [sys.executable, "-c", CHILD, *map(str, files)], capture_output=True, text=True, timeout=120, env=env
    )
    assert result.returncode == 0, result.stderr[-2000:]
    lines = result.stdout.splitlines()
    assert len(lines) == len(files)
    for line, path in zip(lines, files):
        assert line.startswith(f"ERROR {path}:"), line
    assert result.stderr == ""
