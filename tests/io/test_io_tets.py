"""Unstructured grids become clean tetrahedra: split, dropped, reoriented, and all of it reported."""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv
from pyvista import examples

from volren.errors import VolrenError, VolrenWarning
from volren.io import from_pyvista, load_volume
from volren.model.tet_repair import signed_volumes


def single(points, cell_type) -> pv.UnstructuredGrid:
    points = np.asarray(points, dtype=float)
    return pv.UnstructuredGrid(
        np.array([len(points), *range(len(points))]), np.array([cell_type], np.uint8), points
    )


def merged(*cells: pv.UnstructuredGrid, extra_points: int = 0) -> pv.UnstructuredGrid:
    """One grid holding the given single-cell grids side by side (2 units apart along x)."""
    points, conn, types = [], [], []
    offset = 0
    for n, cell in enumerate(cells):
        points.append(np.asarray(cell.points) + [2.0 * n, 0, 0])
        for c in range(cell.n_cells):
            ids = cell.get_cell(c).point_ids
            conn += [len(ids), *(offset + i for i in ids)]
            types.append(cell.celltypes[c])
        offset += cell.n_points
    points.append(np.full((extra_points, 3), 99.0))  # unreferenced points are fine
    grid = pv.UnstructuredGrid(np.array(conn), np.array(types, np.uint8), np.vstack(points))
    grid.point_data["s"] = np.arange(grid.n_points, dtype=np.float32)
    return grid


def solid_volume(grid: pv.UnstructuredGrid) -> float:
    sizes = grid.compute_cell_sizes(length=False, area=False, volume=True)
    return float(np.abs(sizes.cell_data["Volume"]).sum())


TET = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
# VTK's wedge: the base (0, 1, 2) faces away from the top (3, 4, 5). pyvista's example wedge is the
# other way round, so VTK splits it into inverted tetrahedra (which the loader reorients).
WEDGE = single([[0, 0, 0], [0, 1, 0], [1, 0, 0], [0, 0, 1], [0, 1, 1], [1, 0, 1]], pv.CellType.WEDGE)
INVERTED_TET = [[0, 0, 0], [0, 1, 0], [1, 0, 0], [0, 0, 1]]
FLAT_TET = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]


@pytest.mark.parametrize(
    "cell, name",
    [(examples.cells.Hexahedron(), "hexahedron"), (WEDGE, "wedge"), (examples.cells.Pyramid(), "pyramid"),
     (examples.cells.Voxel(), "voxel")],
)  # fmt: skip
def test_each_cell_type_keeps_its_volume(cell, name):
    grid = merged(cell)
    with pytest.warns(VolrenWarning, match=f"^g: tetrahedralized 1 {name}$"):
        volume = from_pyvista(grid, name="g")
    volumes = signed_volumes(volume.points, volume.tets)
    assert np.all(volumes > 0)
    assert volumes.sum() == pytest.approx(solid_volume(grid), rel=1e-12)
    np.testing.assert_array_equal(volume.values, grid.point_data["s"])


def test_mixed_grid_repairs_are_counted_once(tmp_path):
    hexes = pv.StructuredGrid(*np.meshgrid(np.arange(4.0), np.arange(3.0), np.arange(2.0), indexing="ij"))
    tetra = pv.CellType.TETRA
    parts = [
        hexes.cast_to_unstructured_grid(), WEDGE, examples.cells.Pyramid(),
        single(TET, tetra), single(INVERTED_TET, tetra), single(FLAT_TET, tetra),
        single([[0, 0, 0], [1, 0, 0], [0, 1, 0]], pv.CellType.TRIANGLE),
        single([[0, 0, 0], [1, 0, 0]], pv.CellType.LINE),
    ]  # fmt: skip
    grid = merged(*parts, extra_points=3)
    summary = (
        "mixed.vtu: tetrahedralized 6 hexahedra, 1 wedge, 1 pyramid, "
        "dropped 2 cells that are not 3D (1 line, 1 triangle), "
        "dropped 1 zero-volume tetrahedron, reoriented 1 inverted tetrahedron"
    )
    grid.save(tmp_path / "mixed.vtu")
    with pytest.warns(VolrenWarning) as record:
        volume = load_volume(tmp_path / "mixed.vtu")
    assert [str(w.message) for w in record] == [summary]  # one warning for all repairs
    assert volume.notes == (summary,)
    volumes = signed_volumes(volume.points, volume.tets)
    assert np.all(volumes > 0)
    solids = grid.extract_cells(np.flatnonzero(np.isin(grid.celltypes, [10, 12, 13, 14])))
    assert volumes.sum() == pytest.approx(solid_volume(solids), rel=1e-12)
    assert len(volume.points) == grid.n_points  # unreferenced points stay; nothing renumbered
    np.testing.assert_array_equal(volume.values, grid.point_data["s"])
    # legacy files go through the same path
    grid.save(tmp_path / "mixed.vtk")
    with pytest.warns(VolrenWarning, match="^mixed.vtk: tetrahedralized 6 hexahedra"):
        assert len(load_volume(tmp_path / "mixed.vtk").tets) == len(volume.tets)


def test_inverted_cells_are_reoriented():
    with pytest.warns(VolrenWarning, match="^w: tetrahedralized 1 wedge, reoriented 3 inverted tetrahedra$"):
        volume = from_pyvista(merged(examples.cells.Wedge()), name="w")
    assert np.all(signed_volumes(volume.points, volume.tets) > 0)


def test_inverted_tet_is_reoriented():
    with pytest.warns(VolrenWarning, match="^t: reoriented 1 inverted tetrahedron$"):
        volume = from_pyvista(merged(single(INVERTED_TET, pv.CellType.TETRA)), name="t")
    assert signed_volumes(volume.points, volume.tets)[0] == pytest.approx(1 / 6)


def test_cells_folded_over_a_neighbour_are_reported():
    points = [*TET, [0.1, 0.1, 0.1]]  # the second cell's apex lies on the first one's side
    grid = pv.UnstructuredGrid(np.array([4, 0, 1, 2, 3, 4, 1, 2, 3, 4]), np.full(2, pv.CellType.TETRA, np.uint8),
                               np.array(points, dtype=float))  # fmt: skip
    grid.point_data["s"] = np.arange(5, dtype=np.float32)
    with pytest.warns(VolrenWarning) as record:
        volume = from_pyvista(grid, name="fold")
    fold_note = "fold: 2 tetrahedra fold over a neighbour (a tangled mesh)"
    assert [str(w.message) for w in record] == ["fold: reoriented 1 inverted tetrahedron", fold_note]
    assert fold_note in volume.notes


def test_flat_tets_alone_are_an_error():
    with pytest.raises(VolrenError, match="^flat: all 1 tetrahedra have zero volume$"):
        from_pyvista(merged(single(FLAT_TET, pv.CellType.TETRA)), name="flat")


def test_cell_scalars_are_moved_to_points():
    grid = merged(single(TET, pv.CellType.TETRA), single(TET, pv.CellType.TETRA))
    grid.cell_data["c"] = np.array([2.0, 4.0], dtype=np.float32)
    with pytest.warns(VolrenWarning, match="^cells: array 'c' is cell data; averaged it onto the points$"):
        volume = from_pyvista(grid, scalars="c", name="cells")
    np.testing.assert_array_equal(volume.values, [2, 2, 2, 2, 4, 4, 4, 4])


def test_grids_without_3d_cells_or_points():
    with pytest.raises(VolrenError, match=r"^tri: no 3D cells to render \(the grid holds 1 triangle\)$"):
        from_pyvista(merged(single([[0, 0, 0], [1, 0, 0], [0, 1, 0]], pv.CellType.TRIANGLE)), name="tri")
    empty = pv.UnstructuredGrid()
    with pytest.raises(VolrenError, match=r"^empty: the grid is empty \(0 points, 0 cells\)$"):
        from_pyvista(empty, name="empty")


def test_duplicated_tets_are_merged_and_reported():
    grid = merged(single(TET, pv.CellType.TETRA))
    doubled = pv.UnstructuredGrid(
        np.array([4, 0, 1, 2, 3, 4, 3, 2, 1, 0]), np.full(2, pv.CellType.TETRA, np.uint8), grid.points
    )
    doubled.point_data["s"] = grid.point_data["s"]
    with pytest.warns(VolrenWarning, match="^d: 1 duplicated tetrahedron merged$"):
        volume = from_pyvista(doubled, name="d")
    assert len(volume.tets) == 1 and volume.merged_tet_count == 1


def test_the_cell_types_known_without_pyvista_are_pyvistas():
    """A cell of a type VTK does not define is broken (`_pv.broken_cells`): the list kept to read meshes
    without importing PyVista is its CellType enum."""
    import pyvista as pv

    from volren.io import _pv

    assert sorted(_pv.VTK_CELL_TYPES) == sorted(int(c) for c in pv.CellType)
