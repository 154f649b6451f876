"""Label volumes from files (`volren.io.label_io`) and label-info files (`volren.io.label_info`):
every grid format read with its labels exact, 3D Slicer's .seg.nrrd segment keys, and one-line
refusals naming the file."""

from __future__ import annotations

import gzip
import json

import numpy as np
import pytest
import pyvista as pv
import vtk

from volren.errors import VolrenError
from volren.io import save_transfer_function
from volren.io.label_info import load_label_info
from volren.io.label_io import load_labels
from volren.model.labels import LabelMap
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TransferFunction2D
from volren.model.volume import UniformVolume

SPACING = (0.5, 0.75, 2.0)
ORIGIN = (10.0, -20.0, 30.0)
SHAPE = (4, 5, 6)  # nz, ny, nx


def image(values: np.ndarray, spacing=SPACING, origin=ORIGIN) -> pv.ImageData:
    nz, ny, nx = values.shape
    img = pv.ImageData(dimensions=(nx, ny, nz), spacing=spacing, origin=origin)
    img.point_data["labels"] = values.ravel()
    return img


def volume() -> UniformVolume:
    """The intensity volume the labels segment: SHAPE on SPACING and ORIGIN."""
    return UniformVolume(
        np.arange(np.prod(SHAPE), dtype=np.float32).reshape(SHAPE), SPACING, ORIGIN, name="ct.vti"
    )


def labels_of(dtype, top: int = 6) -> np.ndarray:
    """Labels 0..top (and `top` itself at one corner), every value a whole number."""
    values = (np.arange(np.prod(SHAPE)).reshape(SHAPE) % 7).astype(dtype)
    values[0, 0, 0] = top
    return values


def nrrd_text(values: np.ndarray, extra: str = "", encoding: str = "raw", sizes: str | None = None,
              dimension: int = 3, kinds: str = "domain domain domain") -> bytes:  # fmt: skip
    nz, ny, nx = values.shape
    kind = {np.dtype(np.uint8): "uchar", np.dtype(np.uint16): "ushort", np.dtype(np.int16): "short"}[
        values.dtype
    ]
    sx, sy, sz = SPACING
    lines = ["NRRD0004", f"type: {kind}", f"dimension: {dimension}", f"sizes: {sizes or f'{nx} {ny} {nz}'}",
             f"space directions: ({sx},0,0) (0,{sy},0) (0,0,{sz})" if dimension == 3 else
             f"space directions: none ({sx},0,0) (0,{sy},0) (0,0,{sz})",
             "space origin: ({},{},{})".format(*ORIGIN), "endian: little", f"encoding: {encoding}", f"kinds: {kinds}"]  # fmt: skip
    data = values.astype(values.dtype.newbyteorder("<")).tobytes()
    return ("\n".join(lines) + "\n" + extra + "\n").encode() + (
        gzip.compress(data) if encoding == "gzip" else data
    )


def _vti(v, tmp):
    image(v).save(tmp / "seg.vti")
    return tmp / "seg.vti"


def _nii(v, tmp):
    image(v).save(tmp / "seg.nii")
    return tmp / "seg.nii"


def _nii_gz(v, tmp):
    image(v).save(tmp / "seg.nii.gz")
    return tmp / "seg.nii.gz"


def _mhd(v, tmp):
    writer = vtk.vtkMetaImageWriter()
    writer.SetInputData(image(v))
    writer.SetFileName(str(tmp / "seg.mhd"))
    writer.SetCompression(False)
    writer.Write()
    return tmp / "seg.mhd"


def _nrrd(v, tmp):
    (tmp / "seg.nrrd").write_bytes(nrrd_text(v, encoding="gzip"))
    return tmp / "seg.nrrd"


WRITERS = {"vti": _vti, "nii": _nii, "nii.gz": _nii_gz, "mhd": _mhd, "nrrd-gzip": _nrrd}


@pytest.mark.parametrize(
    ("dtype", "top"), [(np.uint8, 255), (np.uint16, 65535), (np.int32, 300), (np.int16, 9)]
)
@pytest.mark.parametrize("fmt", sorted(WRITERS))
def test_labels_come_back_exact_from_every_grid_format(tmp_path, fmt, dtype, top):
    """Labels are ids, not numbers to rescale or interpolate: each file's values come back as they
    are, as uint8 where every label fits and uint16 beyond."""
    if fmt == "nrrd-gzip" and dtype == np.int32:
        dtype = np.uint16  # the test's NRRD writer knows 8 and 16 bits
    values = labels_of(dtype, top)
    label_map = load_labels(WRITERS[fmt](values, tmp_path), volume())
    assert isinstance(label_map, LabelMap)
    assert label_map.values.dtype == (np.uint8 if top <= 255 else np.uint16)
    np.testing.assert_array_equal(label_map.values, values)
    assert label_map.present == tuple(sorted({*range(7), top}))


@pytest.mark.parametrize(("values", "problem"), [
    (np.full(SHAPE, 1.5, np.float32), "labels must be whole numbers"),
    (np.full(SHAPE, -1, np.int16), "labels must lie in 0..65535, found -1..-1"),
    (np.full(SHAPE, 70000, np.int32), "labels must lie in 0..65535, found 70000..70000"),
])  # fmt: skip
def test_values_that_are_not_labels_are_refused_naming_the_file(tmp_path, values, problem):
    path = _nii_gz(values, tmp_path)
    with pytest.raises(VolrenError, match=rf"^seg\.nii\.gz: {problem}"):
        load_labels(path, volume())


def test_labels_on_another_grid_are_refused_saying_both(tmp_path):
    values = labels_of(np.uint8)
    path = _vti(values[:, :, :5], tmp_path)
    with pytest.raises(VolrenError) as exc:
        load_labels(path, volume())
    assert str(exc.value) == (f"{path}: the label volume is 5x5x4 but ct.vti is 6x5x4: labels must lie on the "
                              "volume's grid")  # fmt: skip
    image(values, spacing=(0.5, 0.75, 2.1)).save(tmp_path / "s.vti")
    with pytest.raises(
        VolrenError, match=r"spacing \(0.5, 0.75, 2.1\) differs from ct.vti's \(0.5, 0.75, 2\)"
    ):
        load_labels(tmp_path / "s.vti", volume())
    image(values, origin=(10.0, -20.0, 30.5)).save(tmp_path / "o.vti")
    with pytest.raises(VolrenError, match=r"origin \(10, -20, 30.5\) differs from ct.vti's \(10, -20, 30\)"):
        load_labels(tmp_path / "o.vti", volume())


def test_a_grid_within_the_tolerance_is_the_same_grid(tmp_path):
    """Tools print spacings and origins to six digits: 2.00001 for 2 and an origin a thousandth
    of a voxel off are the volume's grid."""
    values = labels_of(np.uint8)
    image(values, spacing=(0.5, 0.75, 2.00001), origin=(10.0, -20.0005, 30.0)).save(tmp_path / "t.vti")
    np.testing.assert_array_equal(load_labels(tmp_path / "t.vti", volume()).values, values)


def test_a_mesh_a_vector_and_a_missing_file_are_refused(tmp_path):
    with pytest.raises(VolrenError, match=r"nowhere.nii.gz: no such file"):
        load_labels(tmp_path / "nowhere.nii.gz", volume())
    vectors = image(labels_of(np.uint8))
    vectors.point_data["labels"] = np.ones((vectors.n_points, 3), np.uint8)
    vectors.save(tmp_path / "v.vti")
    with pytest.raises(VolrenError, match=r"v.vti: array 'labels' has several components"):
        load_labels(tmp_path / "v.vti", volume())
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float64)
    mesh = pv.UnstructuredGrid(np.array([4, 0, 1, 2, 3]), np.array([pv.CellType.TETRA]), points)
    mesh.point_data["labels"] = np.zeros(mesh.n_points, np.uint8)
    mesh.save(tmp_path / "m.vtu")
    with pytest.raises(VolrenError, match=r"m.vtu: is a tetrahedral mesh"):
        load_labels(tmp_path / "m.vtu", volume())


SLICER_KEYS = """Segment0_Color:=0.5 0.25 1
Segment0_ID:=Segment_1
Segment0_LabelValue:=3
Segment0_Layer:=0
Segment0_Name:=liver
Segment1_Color:=0 1 0
Segment1_LabelValue:=5
Segment1_Layer:=0
Segment1_Name:=left kidney
Segmentation_MasterRepresentation:=Binary labelmap
"""


def test_a_slicer_seg_nrrd_brings_its_segments_names_and_colours(tmp_path):
    values = np.where(labels_of(np.uint8) % 2 == 0, 3, 5).astype(np.uint8)
    path = tmp_path / "organs.seg.nrrd"
    path.write_bytes(nrrd_text(values, SLICER_KEYS, encoding="gzip"))
    label_map = load_labels(path, volume())
    np.testing.assert_array_equal(label_map.values, values)
    assert label_map.names == {3: "liver", 5: "left kidney"}
    assert label_map.colors == {3: (0.5, 0.25, 1.0), 5: (0.0, 1.0, 0.0)}


@pytest.mark.parametrize(("keys", "problem"), [
    (SLICER_KEYS.replace("Segment1_Layer:=0", "Segment1_Layer:=1"), "a segmentation of 2 layers"),
    (SLICER_KEYS.replace("Segment1_LabelValue:=5\n", ""), "Segment1_LabelValue is missing"),
    (SLICER_KEYS.replace("Segment1_LabelValue:=5", "Segment1_LabelValue:=x"), "Segment1_LabelValue 'x' is not a whole"),
    (SLICER_KEYS.replace("Segment0_Color:=0.5 0.25 1", "Segment0_Color:=0.5 0.25"), "Segment0_Color '0.5 0.25' must"),
])  # fmt: skip
def test_a_seg_nrrd_with_bad_segment_keys_is_refused_naming_the_key(tmp_path, keys, problem):
    path = tmp_path / "organs.seg.nrrd"
    path.write_bytes(nrrd_text(labels_of(np.uint8), keys))
    with pytest.raises(VolrenError, match=rf"^{path}: {problem}"):
        load_labels(path, volume())


def test_a_multi_layer_seg_nrrd_is_refused_with_what_to_do(tmp_path):
    """Overlapping segments are a 4D file (a layer axis first): one label per voxel cannot hold them."""
    values = np.stack([labels_of(np.uint8)] * 2, axis=-1)  # layers vary fastest
    nz, ny, nx, _ = values.shape
    path = tmp_path / "layers.seg.nrrd"
    path.write_bytes(nrrd_text(values.reshape(nz, ny, nx * 2), SLICER_KEYS, sizes=f"2 {nx} {ny} {nz}", dimension=4,
                               kinds="list domain domain domain"))  # fmt: skip
    with pytest.raises(VolrenError) as exc:
        load_labels(path, volume())
    assert str(exc.value).startswith(f"{path}: a segmentation of 2 layers (overlapping segments)")
    assert "save it with one layer" in str(exc.value)


def test_label_info_names_colours_and_styles(tmp_path):
    (tmp_path / "tfs").mkdir()
    bone = TransferFunction1D.ramp(0, 100, 0.8)
    save_transfer_function(bone, tmp_path / "tfs" / "bone.json")
    inline = TransferFunction1D.ramp(0, 10, 0.5)
    info = {"version": 1, "labels": {
        "3": {"name": "liver", "color": [0.8, 0.3, 0.2], "opacity": 0.5},
        "4": {"name": "bone", "tf": "tfs/bone.json", "visible": True},
        "7": {"tf": inline.to_dict(), "visible": False},
        "9": {"name": "only a name"},
    }}  # fmt: skip
    (tmp_path / "labels.json").write_text(json.dumps(info))
    got = load_label_info(tmp_path / "labels.json")
    assert got.names == {3: "liver", 4: "bone", 9: "only a name"}
    assert got.colors == {3: (0.8, 0.3, 0.2)}
    assert got.styles[3] == {"color": (0.8, 0.3, 0.2), "opacity": 0.5}
    assert set(got.styles[4]) == {"tf", "visible"} and got.styles[4]["tf"] == bone
    assert got.styles[7]["tf"] == inline and got.styles[7]["visible"] is False
    assert 9 not in got.styles


@pytest.mark.parametrize(("info", "problem"), [
    ({"version": 2, "labels": {}}, "label info format version 2 is newer"),
    ({"version": 1, "labels": {"x": {}}}, "labels: a label is a whole number in 0..65535, got 'x'"),
    ({"version": 1, "labels": {"3": {"colour": [1, 0, 0]}}}, "label 3: unknown key\\(s\\) colour"),
    ({"version": 1, "labels": {"3": {"opacity": "half"}}}, "label 3: 'opacity' must be a number"),
    ({"version": 1, "labels": {"3": {"color": [2, 0, 0]}}}, "label 3: a colour is three numbers in \\[0, 1\\]"),
    ({"version": 1, "labels": {"3": {"tf": "missing.json"}}}, "label 3: tf: .*missing.json: no such file"),
    ({"version": 1, "labels": {"3": {"tf": TransferFunction2D((0, 1), (0, 1)).to_dict()}}},
     "label 3: tf: a label's transfer function is 1D, got a 2D TF"),
    ({"version": 1, "lables": {}}, "unknown key\\(s\\) lables"),
])  # fmt: skip
def test_a_bad_label_info_is_one_line_naming_the_file(tmp_path, info, problem):
    path = tmp_path / "labels.json"
    path.write_text(json.dumps(info))
    with pytest.raises(VolrenError, match=rf"^{path}: {problem}"):
        load_label_info(path)


def test_label_info_in_the_list_form_beside_segmentations(tmp_path) -> None:
    """``{"labels": [{"value": N, "name": ..., "color": [...]}]}`` without a version, as the label
    files of the shared frog and PD25 segmentations give them."""
    import json

    from volren.io.label_info import load_label_info

    path = tmp_path / "seg.labels.json"
    path.write_text(json.dumps({"labels": [{"value": 1, "name": "blood", "color": [0.8, 0.1, 0.1]},
                                           {"value": 12, "name": "nerve", "color": [1.0, 1.0, 0.5]}]}))  # fmt: skip
    info = load_label_info(path)
    assert info.names == {1: "blood", 12: "nerve"}
    assert info.colors[12] == (1.0, 1.0, 0.5)
    path.write_text(json.dumps({"labels": [{"value": 1}, {"value": 1}]}))
    with pytest.raises(VolrenError, match="listed twice") as error:
        load_label_info(path)
    assert str(path) in str(error.value)
    path.write_text(json.dumps({"labels": [{"name": "x"}]}))
    with pytest.raises(VolrenError, match="'value'"):
        load_label_info(path)
