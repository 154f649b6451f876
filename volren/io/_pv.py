"""The one place in volren.io that imports VTK and PyVista.

Everything else in the package sees plain numpy through `DatasetView` and the helpers below, so the
rules about what VTK does (which reader, how its messages are caught, how cells are split into
tetrahedra, how ParaView's colour and opacity interpolation behave) live in one module.

Image data is seen through VTK's own API, and PyVista is imported only where a mesh, a write or a
dataset that is not image data needs it: its import takes a quarter of a second, a third of what a
one-shot `volren render` of a grid spends starting up. VTK's modules are imported where a reader,
filter or colour function needs them, for the same reason (60 ms of a render's imports).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkDataArray, vtkStringArray
from vtkmodules.vtkCommonDataModel import vtkImageData, vtkPiecewiseFunction, vtkUnstructuredGrid

try:  # VTK >= 9.6 moved the static cell-type helpers here
    from vtkmodules.vtkCommonDataModel import vtkCellTypeUtilities as _CellTypes
except ImportError:  # pragma: no cover - older VTK
    from vtkmodules.vtkCommonDataModel import vtkCellTypes as _CellTypes

VTK_TETRA = 10

# --------------------------------------------------------------------------- VTK's messages

from volren.vtk_messages import MessageLog, VtkMessage, vtk_messages  # noqa: E402,F401  (re-exported)


def _pyvista() -> Any:
    """PyVista, imported on first use (see the module's docstring)."""
    import pyvista

    return pyvista


# ------------------------------------------------------------------------------- dataset views


@dataclass(frozen=True)
class DatasetView:
    """What a VTK dataset holds, as numpy; `handle` is the dataset for later VTK work."""

    handle: Any
    kind: Literal["image", "unstructured"]
    n_points: int
    n_cells: int
    point_arrays: Mapping[str, NDArray]
    cell_arrays: Mapping[str, NDArray]
    field_arrays: Mapping[str, NDArray]
    active_point: str | None = None
    active_cell: str | None = None
    # image data only
    dimensions: tuple[int, int, int] = (0, 0, 0)
    spacing: tuple[float, float, float] = (1.0, 1.0, 1.0)
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0)
    direction: NDArray | None = None
    # unstructured grids only
    n_connectivity: int = 0
    type_name: str = ""
    #: the names VTK gives an array's components (None where unnamed), for arrays of several
    component_names: Mapping[str, tuple[str | None, ...]] = field(default_factory=dict)


def _vtk_array(array: Any) -> NDArray | None:
    """A VTK array as numpy (a view that keeps the VTK array alive), or None for other kinds."""
    if isinstance(array, vtkDataArray):
        return np.asarray(vtk_to_numpy(array))
    if isinstance(array, vtkStringArray):
        return np.array([array.GetValue(i) for i in range(array.GetNumberOfValues())], dtype=str)
    return None


def _vtk_arrays(data: Any) -> dict[str, NDArray]:
    """A VTK attribute set's (or field data's) named arrays (pyvista's datasets are VTK's too)."""
    out = {}
    for i in range(data.GetNumberOfArrays()):
        array = data.GetAbstractArray(i)
        name = array.GetName() if array is not None else None
        values = _vtk_array(array) if name else None
        if values is not None:
            out[str(name)] = values
    return out


def _component_names(*sets: Any) -> dict[str, tuple[str | None, ...]]:
    """The component names of the arrays of several components in these attribute sets."""
    out: dict[str, tuple[str | None, ...]] = {}
    for data in sets:
        for i in range(data.GetNumberOfArrays()):
            array = data.GetAbstractArray(i)
            count = array.GetNumberOfComponents() if array is not None else 0
            if count > 1 and array.GetName() and array.HasAComponentName():
                names = tuple(array.GetComponentName(c) for c in range(count))
                out.setdefault(str(array.GetName()), tuple(str(n) if n else None for n in names))
    return out


def _vtk_active_name(data: Any) -> str | None:
    scalars = data.GetScalars()
    name = scalars.GetName() if scalars is not None else None
    return str(name) if name else None


def as_dataset(obj: Any) -> Any | None:
    """Image data and unstructured grids as they are (VTK's or pyvista's), any other dataset wrapped
    by pyvista, or None when it is not a dataset."""
    if isinstance(obj, vtkImageData | vtkUnstructuredGrid):
        return obj
    pv = _pyvista()
    if isinstance(obj, pv.DataSet):
        return obj
    try:
        wrapped = pv.wrap(obj)
    except (TypeError, NotImplementedError, ValueError, AttributeError):
        return None
    return wrapped if isinstance(wrapped, pv.DataSet) else None


def _image_view(image: Any) -> DatasetView:
    """A `DatasetView` of VTK image data, through VTK's API (pyvista's ImageData is one too)."""
    x0, _, y0, _, z0, _ = image.GetExtent()
    spacing = tuple(float(s) for s in image.GetSpacing())
    # VTK places point (i, j, k) of an extent starting at (x0, y0, z0) at origin + (x0 + i) * s.
    origin = tuple(float(o + e * s) for o, e, s in zip(image.GetOrigin(), (x0, y0, z0), spacing))
    m = image.GetDirectionMatrix()
    direction = np.array([[m.GetElement(i, j) for j in range(3)] for i in range(3)], dtype=np.float64)
    return DatasetView(
        handle=image,
        kind="image",
        n_points=int(image.GetNumberOfPoints()),
        n_cells=int(image.GetNumberOfCells()),
        point_arrays=_vtk_arrays(image.GetPointData()),
        cell_arrays=_vtk_arrays(image.GetCellData()),
        field_arrays=_vtk_arrays(image.GetFieldData()),
        active_point=_vtk_active_name(image.GetPointData()),
        active_cell=_vtk_active_name(image.GetCellData()),
        dimensions=tuple(int(d) for d in image.GetDimensions()),  # type: ignore[arg-type]
        spacing=spacing,  # type: ignore[arg-type]
        origin=origin,  # type: ignore[arg-type]
        direction=direction,
        type_name="ImageData",
        component_names=_component_names(image.GetPointData(), image.GetCellData()),
    )


def view(dataset: Any) -> DatasetView:
    """A `DatasetView` of a dataset from `as_dataset`: image data stays a grid, anything else
    becomes cells (read through VTK's API: a mesh needs no pyvista, whose import costs 0.2-0.4 s)."""
    if isinstance(dataset, vtkImageData):
        return _image_view(dataset)
    if not isinstance(dataset, vtkUnstructuredGrid):
        dataset = dataset.cast_to_unstructured_grid()
    return DatasetView(
        handle=dataset,
        kind="unstructured",
        n_points=int(dataset.GetNumberOfPoints()),
        n_cells=int(dataset.GetNumberOfCells()),
        point_arrays=_vtk_arrays(dataset.GetPointData()),
        cell_arrays=_vtk_arrays(dataset.GetCellData()),
        field_arrays=_vtk_arrays(dataset.GetFieldData()),
        active_point=_vtk_active_name(dataset.GetPointData()),
        active_cell=_vtk_active_name(dataset.GetCellData()),
        n_connectivity=len(_connectivity(dataset)),
        type_name="UnstructuredGrid",
    )


def _numpy(array: Any, dtype: type) -> NDArray:
    """A VTK array as numpy (empty for None)."""
    return np.zeros(0, dtype) if array is None else np.asarray(vtk_to_numpy(array), dtype=dtype)


def _grid_points(grid: Any) -> NDArray[np.float64]:
    points = grid.GetPoints()
    return np.zeros((0, 3)) if points is None else _numpy(points.GetData(), np.float64).reshape(-1, 3)


def _cell_types(grid: Any) -> NDArray[np.int64]:
    try:  # VTK >= 9.6 (where GetCellTypesArray is deprecated)
        types = grid.GetCellTypes()
    except TypeError:  # pragma: no cover - older VTK, whose GetCellTypes fills a vtkCellTypes
        types = grid.GetCellTypesArray()
    return _numpy(types, np.int64)


def _connectivity(grid: Any) -> NDArray[np.int64]:
    cells = grid.GetCells()
    return _numpy(None if cells is None else cells.GetConnectivityArray(), np.int64)


def _cell_offsets(grid: Any) -> NDArray[np.int64]:
    cells = grid.GetCells()
    return _numpy(None if cells is None else cells.GetOffsetsArray(), np.int64)


def _original_point_ids(grid: Any) -> NDArray[np.int64]:
    """The point ids a VTK filter (extract_cells) carried over from its input."""
    return _numpy(grid.GetPointData().GetArray("vtkOriginalPointIds"), np.int64)


def cell_to_point(v: DatasetView) -> DatasetView:
    """Average cell data onto the points (VTK's vtkCellDataToPointData, as pyvista runs it)."""
    from vtkmodules.vtkFiltersCore import vtkCellDataToPointData

    with vtk_messages():
        average = vtkCellDataToPointData()
        average.SetInputDataObject(v.handle)
        average.SetPassCellData(False)
        average.Update()
        converted = average.GetOutputDataObject(0)
    return view(converted)


# ----------------------------------------------------------------------------------- readers

ReaderName = Literal[
    "vti", "vtu", "legacy-image", "legacy-unstructured", "metaimage", "nrrd", "nifti", "slc", "dicom"
]


@dataclass
class ReadResult:
    """A reader's output, what VTK said while reading, and reader-specific facts (`info`)."""

    view: DatasetView | None
    log: MessageLog
    info: dict[str, Any] = field(default_factory=dict)


def _matrix(m: Any) -> NDArray | None:
    if m is None:
        return None
    return np.array([[m.GetElement(i, j) for j in range(4)] for i in range(4)], dtype=np.float64)


def _make_reader(reader: ReaderName) -> Any:
    if reader == "vti":
        from vtkmodules.vtkIOXML import vtkXMLImageDataReader

        return vtkXMLImageDataReader()
    if reader == "vtu":
        from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader

        return vtkXMLUnstructuredGridReader()
    if reader in ("legacy-image", "legacy-unstructured"):
        from vtkmodules.vtkIOLegacy import vtkStructuredPointsReader, vtkUnstructuredGridReader

        r = vtkStructuredPointsReader() if reader == "legacy-image" else vtkUnstructuredGridReader()
        # Legacy readers keep only the first array of each attribute kind unless told otherwise.
        for flag in ("Scalars", "Vectors", "Normals", "Tensors", "ColorScalars", "TCoords", "Fields"):
            getattr(r, f"ReadAll{flag}On")()
        return r
    if reader in ("metaimage", "nrrd", "nifti"):
        from vtkmodules import vtkIOImage

        return {"metaimage": vtkIOImage.vtkMetaImageReader, "nrrd": vtkIOImage.vtkNrrdReader,
                "nifti": vtkIOImage.vtkNIFTIImageReader}[reader]()  # fmt: skip
    # "slc" and "dicom" are read by volren itself (formats/slc.py, formats/dicom.py): VTK's readers
    # of those formats crash or return uninitialized memory on malformed files.
    raise ValueError(f"unknown reader {reader!r}")  # pragma: no cover - programming error


def read(path: Path, reader: ReaderName) -> ReadResult:
    """Run one VTK reader on `path` with its messages caught."""
    r = _make_reader(reader)
    info: dict[str, Any] = {}
    with vtk_messages() as log:
        r.SetFileName(str(path))
        r.Update()
        output = r.GetOutputDataObject(0)
    if reader == "nifti":
        info.update(
            qform=_matrix(r.GetQFormMatrix()),
            sform=_matrix(r.GetSFormMatrix()),
            slope=float(r.GetRescaleSlope()),
            intercept=float(r.GetRescaleIntercept()),
        )
    dataset = as_dataset(output) if output is not None else None
    return ReadResult(view(dataset) if dataset is not None else None, log, info)


# ----------------------------------------------------------------------------------- writing


def image_data(values: NDArray, spacing: Sequence[float], origin: Sequence[float], name: str) -> Any:
    """A pyvista ImageData with `values[k, j, i]` as its active point scalars `name`."""
    nz, ny, nx = values.shape
    pv = _pyvista()
    grid = pv.ImageData(dimensions=(nx, ny, nz), spacing=tuple(spacing), origin=tuple(origin))
    grid.point_data[name] = np.ascontiguousarray(values).reshape(-1)  # x fastest, as VTK stores it
    grid.set_active_scalars(name)
    return grid


def tet_grid(points: NDArray, tets: NDArray, values: NDArray, name: str) -> Any:
    """A pyvista UnstructuredGrid of tetrahedra with point scalars `name`."""
    cells = np.hstack([np.full((len(tets), 1), 4, dtype=np.int64), np.asarray(tets, dtype=np.int64)]).reshape(
        -1
    )
    pv = _pyvista()
    grid = pv.UnstructuredGrid(
        cells, np.full(len(tets), pv.CellType.TETRA, dtype=np.uint8), np.asarray(points)
    )
    grid.point_data[name] = values
    grid.set_active_scalars(name)
    return grid


def save(dataset: Any, path: Path) -> MessageLog:
    """Write with pyvista (the writer follows the suffix); what VTK printed comes back."""
    with vtk_messages() as log:
        dataset.save(path)
    return log


# ----------------------------------------------------------------------------- cells to tets


@dataclass(frozen=True)
class TetCells:
    """Tetrahedra over the dataset's own points, and what was converted or dropped to get them."""

    points: NDArray[np.float64]
    tets: NDArray[np.int64]
    tetrahedralized: dict[int, int]  # VTK cell type -> number of such cells split into tets
    dropped: dict[int, int]  # VTK cell type -> number of cells dropped (not 3D)
    broken: dict[str, int] = field(default_factory=dict)  # why -> number of cells dropped as broken


#: Points per cell of the fixed-size VTK cell types (the others list their own count).
_CELL_SIZES = {1: 1, 3: 2, 5: 3, 8: 4, 9: 4, 10: 4, 11: 8, 12: 8, 13: 6, 14: 5, 15: 10, 16: 12, 21: 3, 22: 6,
               23: 8, 24: 10, 25: 20, 26: 15, 27: 13, 28: 9, 29: 27}  # fmt: skip
_SIZE_OF_TYPE = np.full(256, -1, np.int64)  # -1: the type lists its own count
_SIZE_OF_TYPE[list(_CELL_SIZES)] = list(_CELL_SIZES.values())


#: The cell types VTK defines (vtkCellType.h's enum: what pyvista.CellType lists), by value.
VTK_CELL_TYPES = (0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 21, 22, 23, 24, 25, 26, 27, 28, 29, 30, 31,
                  32, 33, 34, 35, 36, 37, 41, 42, 51, 52, 53, 54, 55, 56, 60, 61, 62, 63, 64, 65, 66, 67, 68, 69, 70,
                  71, 72, 73, 74, 75, 76, 77, 78, 79, 80, 81)  # fmt: skip


def broken_cells(grid: Any) -> tuple[NDArray[np.bool_], dict[str, int]]:
    """Cells no VTK filter may touch: an unknown cell type, a point index outside the points
    (VTK reads past its arrays, or -1 as the last point), or a fixed-size type with another count.
    Returns the mask of broken cells and their counts by reason."""
    types = _cell_types(grid)
    offsets = _cell_offsets(grid)
    conn = _connectivity(grid)
    sizes = np.diff(offsets)
    if len(sizes) != len(types) or (offsets.size and (offsets[-1] != conn.size or (sizes < 0).any())):
        return np.ones(len(types), bool), {
            "in a cell list that disagrees with its types and offsets": len(types)
        }
    known = np.isin(types, VTK_CELL_TYPES)
    expected = np.where((types >= 0) & (types < 256), _SIZE_OF_TYPE[np.clip(types, 0, 255)], -1)
    wrong_size = (expected >= 0) & (sizes != expected)
    outside = (conn < 0) | (conn >= int(grid.GetNumberOfPoints()))
    cell_of = np.repeat(np.arange(len(sizes)), np.maximum(sizes, 0))
    bad_index = np.zeros(len(sizes), bool)
    if outside.any() and cell_of.size == conn.size:
        bad_index[cell_of[outside]] = True
    reasons = {
        "of an unknown cell type": ~known,
        "with a point index outside the points": known & bad_index,
        "with the wrong number of points for their type": known & ~bad_index & wrong_size,
    }
    counts = {why: int(mask.sum()) for why, mask in reasons.items() if mask.any()}
    return ~known | bad_index | wrong_size, counts


def cell_type_dimension(cell_type: int) -> int:
    return int(_CellTypes.GetDimension(int(cell_type)))


def cell_type_class(cell_type: int) -> str:
    return str(_CellTypes.GetClassNameFromTypeId(int(cell_type)))


def tetrahedralize(v: DatasetView) -> TetCells:
    """Tetrahedra of the 3D cells; lower-dimensional cells are dropped and counted."""
    grid = v.handle
    points = _grid_points(grid)
    types = _cell_types(grid)
    if types.size == 0:
        return TetCells(points, np.zeros((0, 4), np.int64), {}, {})
    broken, why = broken_cells(grid)
    if broken.any():
        with vtk_messages():
            grid = _pyvista().wrap(grid).extract_cells(np.flatnonzero(~broken))
        if grid.n_cells == 0:
            return TetCells(points, np.zeros((0, 4), np.int64), {}, {}, why)
        cells = tetrahedralize(view(grid))
        ids = _original_point_ids(grid)
        return TetCells(points, ids[cells.tets], cells.tetrahedralized, cells.dropped, why)
    unique, counts = np.unique(types, return_counts=True)
    dims = {int(t): cell_type_dimension(int(t)) for t in unique}
    dropped = {int(t): int(c) for t, c in zip(unique, counts) if dims[int(t)] != 3}
    converted = {int(t): int(c) for t, c in zip(unique, counts) if dims[int(t)] == 3 and t != VTK_TETRA}
    if not dropped and not converted:  # the common case: nothing but tetrahedra
        tets = _connectivity(grid).reshape(-1, 4)
        return TetCells(points, tets, {}, {})
    keep = np.flatnonzero(np.isin(types, [t for t, d in dims.items() if d == 3]))
    if keep.size == 0:
        return TetCells(points, np.zeros((0, 4), np.int64), {}, dropped)
    with vtk_messages():
        # extract_cells renumbers the points; its vtkOriginalPointIds map them back, so the
        # tetrahedra index the dataset's own points (and their values) unchanged.
        solid = _pyvista().wrap(grid).extract_cells(keep)
        tetra = solid.triangulate() if converted else solid
    tet_types = _cell_types(tetra)
    conn = _connectivity(tetra)
    offsets = _cell_offsets(tetra)
    sizes = np.diff(offsets)
    is_tet = (tet_types == VTK_TETRA) & (sizes == 4)
    starts = offsets[:-1][is_tet]
    local = conn[starts[:, None] + np.arange(4)]
    return TetCells(points, _original_point_ids(tetra)[local], converted, dropped)


# ----------------------------------------------------------------- ParaView colour interpolation

#: ParaView's colour space names -> vtkColorTransferFunction's setter of that space.
_COLOR_SPACES: dict[str, str] = {
    "rgb": "SetColorSpaceToRGB",
    "hsv": "SetColorSpaceToHSV",
    "lab": "SetColorSpaceToLab",
    "cielab": "SetColorSpaceToLab",
    "lab/ciede2000": "SetColorSpaceToLabCIEDE2000",
    "ciede2000": "SetColorSpaceToLabCIEDE2000",
    "diverging": "SetColorSpaceToDiverging",
    "step": "SetColorSpaceToStep",
}

COLOR_SPACES = tuple(sorted(_COLOR_SPACES))


Table = Callable[[float, float, int], NDArray]


def color_table(
    nodes: Sequence[Sequence[float]],
    color_space: str = "RGB",
    hsv_wrap: bool = False,
    log_scale: bool = False,
) -> Table:
    """vtkColorTransferFunction through [x, r, g, b] nodes: table(x0, x1, n) -> (n, 3) colours.

    Tables, not single values: VTK's Lab/CIEDE2000 space rebuilds its colour path on every call.
    """
    from vtkmodules.vtkRenderingCore import vtkColorTransferFunction

    ctf = vtkColorTransferFunction()
    getattr(ctf, _COLOR_SPACES[color_space.lower()])()
    ctf.SetHSVWrap(bool(hsv_wrap))
    if log_scale:
        ctf.SetScaleToLog10()
    for x, r, g, b in nodes:
        ctf.AddRGBPoint(float(x), float(r), float(g), float(b))

    def table(x0: float, x1: float, n: int) -> NDArray:
        out = np.zeros(3 * n, dtype=np.float64)
        ctf.GetTable(float(x0), float(x1), int(n), out)
        return out.reshape(n, 3)

    return table


def opacity_table(nodes: Sequence[Sequence[float]]) -> Table:
    """vtkPiecewiseFunction through [x, a, midpoint, sharpness] nodes: table(x0, x1, n) -> (n, 1)."""
    pwf = vtkPiecewiseFunction()
    for x, a, mid, sharp in nodes:
        pwf.AddPoint(float(x), float(a), float(mid), float(sharp))

    def table(x0: float, x1: float, n: int) -> NDArray:
        out = np.zeros(n, dtype=np.float64)
        pwf.GetTable(float(x0), float(x1), int(n), out)
        return out.reshape(n, 1)

    return table
