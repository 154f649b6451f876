"""Mesh preparation for the tetrahedral ray caster: orientation, adjacency, planes, gradients, cache."""

from __future__ import annotations

import itertools
import warnings

import numpy as np
import pytest

from tests.session_policy import SHARED_MISSING
from volren.model import tet_mesh
from volren.model.tet_mesh import FACE_VERTICES, PreparedMesh, build_mesh, prepare_mesh
from volren.model.tet_repair import repair_tets
from volren.model.volume import TetVolume

CUBE = np.array([[i, j, k] for k in (0, 1) for j in (0, 1) for i in (0, 1)], dtype=np.float64)  # i + 2j + 4k
CUBE_5 = np.array([[0, 1, 2, 4], [3, 1, 2, 7], [5, 1, 4, 7], [6, 2, 4, 7], [1, 2, 4, 7]])
CUBE_6 = np.array(
    [[0, 0 + a, 0 + a + b, 7] for a, b, _ in itertools.permutations((1, 2, 4))]  # Kuhn split
)


@pytest.fixture(autouse=True)
def isolated_cache(tmp_path, monkeypatch):
    """Every test gets its own disk cache folder and an empty in-process cache."""
    monkeypatch.setenv(tet_mesh.CACHE_ENV, str(tmp_path / "mesh-cache"))
    tet_mesh.clear_memory_cache()
    yield
    tet_mesh.clear_memory_cache()


def signed_volumes(points, tets):
    p = points[tets]
    return np.linalg.det(p[:, 1:] - p[:, :1]) / 6.0


def grid_mesh(shape=(4, 3, 5), jitter=0.15, seed=0):
    """A jittered structured grid of hexahedra, each Kuhn-split into 6 tets (a conforming mesh)."""
    rng = np.random.default_rng(seed)
    nx, ny, nz = shape
    ijk = np.stack(np.meshgrid(np.arange(nx + 1), np.arange(ny + 1), np.arange(nz + 1), indexing="ij"), -1)
    points = ijk.reshape(-1, 3).astype(np.float64)
    points += rng.uniform(-jitter, jitter, points.shape)
    index = np.arange(len(points)).reshape(nx + 1, ny + 1, nz + 1)
    tets = []
    for i, j, k in itertools.product(range(nx), range(ny), range(nz)):
        corner = [index[i + (c & 1), j + (c >> 1 & 1), k + (c >> 2 & 1)] for c in range(8)]
        tets += [[corner[v] for v in tet] for tet in CUBE_6]
    return points, np.array(tets)


def check_adjacency(mesh: PreparedMesh) -> None:
    a, f = mesh.neighbors, mesh.neighbor_faces
    inner = a >= 0
    t, i = np.nonzero(inner)
    assert np.array_equal(a[a[inner], f[inner]], t)
    assert np.array_equal(f[a[inner], f[inner]], i)
    assert np.all(f[~inner] == -1)
    # The neighbour across face i holds exactly the three vertices of that face.
    mine = np.sort(mesh.tets[t[:, None], FACE_VERTICES[i]], axis=1)
    theirs = np.sort(mesh.tets[a[inner][:, None], FACE_VERTICES[f[inner]]], axis=1)
    assert np.array_equal(mine, theirs)
    # Boundary faces are exactly the faces without a neighbour.
    assert np.array_equal(mesh.boundary_faces, np.argwhere(~inner))


def outward_normals(mesh: PreparedMesh) -> np.ndarray:
    """Unit outward normals (m, 4, 3) from the kernels' planes (sigma n points inward)."""
    p = mesh.planes
    n = -p.sigma[..., None] * p.normals
    with np.errstate(invalid="ignore", divide="ignore"):
        return n / np.linalg.norm(n, axis=2, keepdims=True)


def check_planes(mesh: PreparedMesh) -> None:
    """Each face's vertices on its plane, the opposite vertex on the inner side (sigma n.(x - p_a)
    > 0), the anchor the face's vertex with the lowest id, and usable = neither flat nor
    non-finite."""
    planes = mesh.planes
    assert np.array_equal(planes.usable, ~(mesh.flat | mesh.nonfinite))
    good = ~mesh.flat
    p = mesh.points[mesh.tets[good]]  # (g, 4, 3)
    n, a, sigma = planes.normals[good], planes.anchors[good], planes.sigma[good]
    scale = np.linalg.norm(n, axis=2) * mesh.max_edge_length
    for f in range(4):
        ids = mesh.tets[good][:, FACE_VERTICES[f]]
        assert np.array_equal(a[:, f], mesh.points[ids.min(axis=1)])
        on_face = np.einsum("tij,tj->ti", p[:, FACE_VERTICES[f]] - a[:, f, None], n[:, f])
        assert np.all(np.abs(on_face) <= 1e-12 * scale[:, f, None])
        assert np.all(sigma[:, f] * np.einsum("ij,ij->i", p[:, f] - a[:, f], n[:, f]) > 0)
    assert np.array_equal(planes.values, mesh.values[mesh.tets])


def check_planes_shared(mesh: PreparedMesh) -> None:
    """The two cells of an interior face hold bit-identical planes with opposite sigma."""
    inner = mesh.neighbors >= 0
    across = (mesh.neighbors[inner], mesh.neighbor_faces[inner])
    planes = mesh.planes
    assert np.array_equal(planes.normals[inner], planes.normals[across])
    assert np.array_equal(planes.anchors[inner], planes.anchors[across])
    good = ~(mesh.flat[np.nonzero(inner)[0]] | mesh.flat[across[0]])
    assert np.array_equal(planes.sigma[inner][good], -planes.sigma[across][good])


def check_boundary_outward(mesh: PreparedMesh) -> None:
    """Boundary triangles are the faces' vertices, wound outward: they enclose the mesh volume."""
    t, f = mesh.boundary_faces.T
    assert np.array_equal(mesh.boundary_triangles, mesh.tets[t[:, None], FACE_VERTICES[f]])
    a, b, c = (mesh.points[mesh.boundary_triangles[:, k]] for k in range(3))
    cross = np.cross(b - a, c - a)
    assert np.all(np.einsum("ij,ij->i", cross, outward_normals(mesh)[t, f]) > 0)
    enclosed = np.einsum("ij,ij->i", (a + b + c) / 3, cross).sum() / 6  # divergence theorem
    assert enclosed == pytest.approx(signed_volumes(mesh.points, mesh.tets).sum(), rel=1e-12)


@pytest.mark.parametrize(
    "tets, longest", [(CUBE_5, np.sqrt(2)), (CUBE_6, np.sqrt(3))], ids=["5 tets", "6 tets"]
)
def test_cube_split(tets, longest):
    mesh = build_mesh(CUBE, tets, np.zeros(8))
    assert np.all(signed_volumes(mesh.points, mesh.tets) > 0)
    assert signed_volumes(mesh.points, mesh.tets).sum() == pytest.approx(1.0)
    check_adjacency(mesh)
    check_planes(mesh)
    check_boundary_outward(mesh)
    assert mesh.n_boundary == 12 and mesh.n_flat == 0 and mesh.n_nonmanifold_faces == 0
    assert (mesh.tets.dtype, mesh.neighbors.dtype, mesh.neighbor_faces.dtype) == (np.int32, np.int32, np.int8)
    assert mesh.bounds == (0.0, 1.0, 0.0, 1.0, 0.0, 1.0)
    assert mesh.max_edge_length == pytest.approx(longest)

    # Two boundary triangles per cube face, with the axis normal pointing away from the centre.
    t, f = mesh.boundary_faces.T
    normals = outward_normals(mesh)[t, f]
    centroids = mesh.points[mesh.boundary_triangles].mean(axis=1)
    assert np.all(np.einsum("ij,ij->i", normals, centroids - 0.5) > 0)
    axis = np.argmax(np.abs(normals), axis=1)
    assert np.allclose(np.abs(normals[np.arange(len(axis)), axis]), 1.0)
    sides = [(int(a), bool(normals[k, a] > 0)) for k, a in enumerate(axis)]
    assert sorted(sides.count(side) for side in set(sides)) == [2] * 6


def test_interior_planes_are_exactly_opposite():
    points, tets = grid_mesh()
    mesh = build_mesh(points, tets, np.zeros(len(points)))
    check_adjacency(mesh)
    check_planes(mesh)
    check_boundary_outward(mesh)
    assert mesh.n_boundary == 2 * 2 * (4 * 3 + 3 * 5 + 4 * 5)
    check_planes_shared(mesh)


def test_face_matching_without_packed_keys(monkeypatch):
    """Meshes with more than 2**21 points sort three key columns instead of one packed key."""
    points, tets = grid_mesh(seed=3)
    tets = np.random.default_rng(1).permutation(tets)
    packed = build_mesh(points, tets, np.zeros(len(points)))
    monkeypatch.setattr(tet_mesh, "_PACK_BITS", 2)
    columns = build_mesh(points, tets, np.zeros(len(points)))
    for name in ("neighbors", "neighbor_faces", "boundary_faces", "boundary_triangles"):
        assert np.array_equal(getattr(packed, name), getattr(columns, name))


def test_repeated_points_with_equal_values_are_merged():
    """A mesh whose cells use their own copies of shared points has the adjacency of the shared
    mesh; copies whose values differ (a jump in the field) stay apart."""
    points, tets = grid_mesh(seed=4)
    values = points @ np.array([1.0, -2.0, 0.5])
    shared = build_mesh(points, tets, values)
    pick = np.random.default_rng(2).integers(0, 2, size=tets.shape) * len(points)
    copies = build_mesh(np.concatenate([points, points]), tets + pick, np.concatenate([values, values]))
    for name in ("tets", "neighbors", "neighbor_faces", "boundary_faces"):
        assert np.array_equal(getattr(copies, name), getattr(shared, name)), name
    for name in ("normals", "anchors", "sigma", "values", "usable"):
        assert np.array_equal(getattr(copies.planes, name), getattr(shared.planes, name)), name
    jump = build_mesh(np.concatenate([points, points]), tets + pick, np.concatenate([values, values + 1.0]))
    assert jump.n_boundary > shared.n_boundary
    check_adjacency(jump)
    # -0.0 and 0.0 are the same coordinate
    flipped = np.concatenate([points, np.where(points == 0.0, -0.0, points)])
    assert np.array_equal(
        build_mesh(flipped, tets + pick, np.concatenate([values, values])).neighbors, shared.neighbors
    )


def test_gradients_are_exact_for_a_linear_field():
    points, tets = grid_mesh(seed=2)
    a, b = np.array([0.7, -1.3, 2.1]), 0.4
    mesh = build_mesh(points, tets, points @ a + b)
    assert np.allclose(mesh.gradients, a, rtol=0, atol=1e-12)
    # Eq. 7.2 from vertex 0 reproduces the values at the other vertices.
    x0, s0 = mesh.points[mesh.tets[:, 0]], mesh.values[mesh.tets[:, 0]]
    for k in range(1, 4):
        xk = mesh.points[mesh.tets[:, k]]
        assert np.allclose(s0 + np.einsum("ij,ij->i", mesh.gradients, xk - x0), mesh.values[mesh.tets[:, k]])


def test_an_inverted_tet_is_reoriented():
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], dtype=np.float64)
    tets = np.array([[0, 1, 3, 2], [1, 2, 3, 4]])  # the first is inverted
    assert signed_volumes(points, tets)[0] < 0
    values = points @ np.array([1.0, 2.0, 3.0])
    mesh = build_mesh(points, tets, values)
    assert mesh.n_reoriented == 1
    assert np.array_equal(mesh.tets, [[0, 1, 2, 3], [1, 2, 3, 4]])
    assert np.all(signed_volumes(mesh.points, mesh.tets) > 0)
    assert np.allclose(mesh.gradients, [1.0, 2.0, 3.0])
    check_adjacency(mesh)
    check_planes(mesh)
    check_boundary_outward(mesh)
    assert mesh.n_boundary == 6
    assert np.allclose(outward_normals(mesh)[0, 0], np.ones(3) / np.sqrt(3))  # face 1-2-3, away from 0


def test_flat_tets_are_marked_not_dropped():
    points = np.array(
        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0], [0.3, 0.3, 1e-14]], dtype=np.float64
    )
    tets = np.array(
        [
            [0, 1, 2, 3],  # a proper tet
            [0, 1, 2, 4],  # four coplanar points
            [0, 2, 1, 5],  # nearly flat, and inverted by the 1e-14
            [0, 0, 1, 2],  # repeats a vertex
        ]
    )
    values = np.arange(len(points), dtype=np.float64)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mesh = build_mesh(points, tets, values)
    assert mesh.flat.tolist() == [False, True, True, True] and mesh.n_flat == 3
    assert np.all(mesh.gradients[1:] == 0) and np.all(np.isfinite(mesh.gradients))
    assert mesh.planes.usable.tolist() == [True, False, False, False]
    check_adjacency(mesh)
    check_planes(mesh)
    # Face 0-1-2 is shared by all four cells: non-manifold, so boundary everywhere.
    assert mesh.n_nonmanifold_faces == 1
    assert mesh.neighbors[0, 3] == -1


def test_nonfinite_values_give_nan_gradients():
    points, tets = grid_mesh(shape=(2, 2, 2))
    values = points[:, 0].copy()
    values[5] = np.nan
    values[7] = np.inf
    mesh = build_mesh(points, tets, values)
    touched = np.any(np.isin(tets, [5, 7]), axis=1)
    assert np.array_equal(mesh.nonfinite, touched) and touched.any()
    assert np.all(np.isnan(mesh.gradients[touched]))
    assert np.allclose(mesh.gradients[~touched], [1.0, 0.0, 0.0])
    check_adjacency(mesh)


def test_a_face_shared_by_three_tets_is_counted_and_left_unmatched():
    points = np.array(
        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, -1], [0.2, 0.2, 2]], dtype=np.float64
    )
    tets = np.array([[0, 1, 2, 3], [0, 2, 1, 4], [0, 1, 2, 5]])
    mesh = build_mesh(points, tets, np.zeros(len(points)))
    assert mesh.n_nonmanifold_faces == 1
    assert np.all(mesh.neighbors == -1)
    assert mesh.n_boundary == 12
    check_adjacency(mesh)
    check_planes(mesh)


FOLD_POINTS = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1], [0, 0, 0]], dtype=np.float64)
FOLD_TETS = np.array([[0, 1, 2, 3], [1, 2, 3, 4]])  # apex 4 lies across face 1-2-3 from point 0


def test_a_cell_pushed_through_its_neighbours_face_folds_over_it():
    points = FOLD_POINTS.copy()
    assert not tet_mesh.folded_cells(points, FOLD_TETS).any()
    assert not tet_mesh.folded_cells(points, FOLD_TETS[:, [1, 0, 2, 3]]).any()  # every cell inverted
    points[4] = [0.1, 0.1, 0.1]  # on point 0's side now: cell 1 lies inside cell 0
    assert tet_mesh.folded_cells(points, FOLD_TETS).tolist() == [True, True]
    repaired = repair_tets(points, FOLD_TETS)  # reorienting does not undo a fold
    assert repaired.reoriented == 1
    assert tet_mesh.folded_cells(points, repaired.tets).tolist() == [True, True]


def test_only_a_face_of_two_distinct_cells_with_volume_can_fold():
    points = np.vstack([FOLD_POINTS, [[0.5, 0.5, 0.0]]])  # point 6 lies on face 1-2-3's plane
    points[4] = [0.1, 0.1, 0.1]
    for tets in (
        [[0, 1, 2, 3], [5, 1, 2, 4]],  # point 5 repeats point 0 unmerged: no face is shared
        [[0, 1, 2, 3], [1, 2, 3, 4], [1, 2, 3, 5]],  # face 1-2-3 of three cells matches none
        [[0, 1, 2, 3], [3, 2, 1, 0]],  # a repeated cell, not a fold
        [[0, 1, 2, 3], [1, 2, 3, 6]],  # a flat cell has no sides
    ):
        assert not tet_mesh.folded_cells(points, np.array(tets)).any()


@pytest.mark.parametrize("order", [(0, 1, 2, 3), (1, 0, 2, 3)], ids=["as built", "every cell inverted"])
def test_a_point_pushed_through_a_face_folds_the_cells_around_the_flipped_ones(order):
    """A conforming mesh folds exactly at the faces between cells whose orientation the move flipped
    and cells it did not."""
    points, tets = grid_mesh()
    tets = tets[:, order]
    assert not tet_mesh.folded_cells(points, tets).any()
    before = np.sign(signed_volumes(points, tets))
    pushed = 1 * 4 * 6 + 1 * 6 + 1  # point (1, 1, 1) of the 5x4x6-point grid
    cell = np.flatnonzero((tets == pushed).any(axis=1))[0]
    face = points[tets[cell][tets[cell] != pushed]]
    points[pushed] += 1.5 * (face.mean(axis=0) - points[pushed])  # through the opposite face
    flipped = np.sign(signed_volumes(points, tets)) != before
    neighbors = build_mesh(points, tets, np.zeros(len(points))).neighbors
    across = np.where(neighbors >= 0, flipped[neighbors], flipped[:, None])
    expected = np.any(across != flipped[:, None], axis=1)
    assert 2 <= np.count_nonzero(flipped) and np.array_equal(tet_mesh.folded_cells(points, tets), expected)


def test_result_is_read_only_float64_and_int32():
    mesh = build_mesh(CUBE, CUBE_6, np.zeros(8))
    for name in tet_mesh._ARRAY_FIELDS:
        array = getattr(mesh, name)
        assert not array.flags.writeable, name
    assert mesh.points.dtype == mesh.values.dtype == mesh.planes.normals.dtype == np.float64
    for name in ("normals", "anchors", "sigma", "values", "gradients", "usable"):
        assert not getattr(mesh.planes, name).flags.writeable, name
    assert mesh.boundary_faces.dtype == mesh.boundary_triangles.dtype == np.int32


# --------------------------------------------------------------------------------------------------
# Cache


@pytest.fixture
def counted_builds(monkeypatch):
    calls = []
    real = tet_mesh.build_mesh

    def counting(*args):
        calls.append(1)
        return real(*args)

    monkeypatch.setattr(tet_mesh, "build_mesh", counting)
    return calls


def cube_volume(scale=1.0):
    return TetVolume(CUBE, CUBE_5, CUBE @ np.array([1.0, 2.0, 3.0]) * scale, name="cube")


def same_mesh(a: PreparedMesh, b: PreparedMesh) -> bool:
    arrays = all(np.array_equal(getattr(a, n), getattr(b, n), equal_nan=True) for n in tet_mesh._ARRAY_FIELDS)
    return arrays and (a.n_nonmanifold_faces, a.n_reoriented, a.max_edge_length) == (
        b.n_nonmanifold_faces,
        b.n_reoriented,
        b.max_edge_length,
    )


def test_the_second_call_is_served_from_memory_then_disk(counted_builds):
    first = prepare_mesh(cube_volume())
    assert prepare_mesh(cube_volume()) is first  # another volume object, same content
    assert len(counted_builds) == 1
    path = tet_mesh.cache_path(tet_mesh.content_key(cube_volume()))
    assert path.is_file() and not list(path.parent.glob("*.tmp"))

    tet_mesh.clear_memory_cache()  # as in a new process
    from_disk = prepare_mesh(cube_volume())
    assert len(counted_builds) == 1
    assert from_disk is not first and same_mesh(from_disk, first)
    assert not from_disk.neighbors.flags.writeable

    prepare_mesh(cube_volume(scale=2.0))  # other values: another key
    assert len(counted_builds) == 2


@pytest.mark.parametrize("damage", ["garbage", "truncated", "empty", "other key"])
def test_a_damaged_cache_file_is_rebuilt_and_rewritten(counted_builds, damage):
    volume = cube_volume()
    expected = prepare_mesh(volume)
    path = tet_mesh.cache_path(tet_mesh.content_key(volume))
    good = path.read_bytes()
    if damage == "garbage":
        path.write_bytes(b"not a zip file at all")
    elif damage == "truncated":
        path.write_bytes(good[: len(good) // 2])
    elif damage == "empty":
        path.write_bytes(b"")
    else:  # a valid file stored under the wrong name
        prepare_mesh(cube_volume(scale=3.0))
        path.write_bytes(tet_mesh.cache_path(tet_mesh.content_key(cube_volume(scale=3.0))).read_bytes())
    builds = len(counted_builds)

    tet_mesh.clear_memory_cache()
    assert same_mesh(prepare_mesh(volume), expected)
    assert len(counted_builds) == builds + 1
    tet_mesh.clear_memory_cache()
    assert same_mesh(prepare_mesh(volume), expected)  # the rewritten file serves it now
    assert len(counted_builds) == builds + 1


def test_an_unwritable_cache_folder_is_no_error(tmp_path, monkeypatch, counted_builds):
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    monkeypatch.setenv(tet_mesh.CACHE_ENV, str(blocker / "meshes"))
    mesh = prepare_mesh(cube_volume())
    assert mesh.n_boundary == 12


def test_without_disk_cache_nothing_is_written(counted_builds):
    prepare_mesh(cube_volume(), disk_cache=False)
    assert not tet_mesh.cache_dir().exists()
    assert len(counted_builds) == 1


def test_the_key_covers_points_tets_and_values():
    base = cube_volume()
    keys = {
        tet_mesh.content_key(base),
        tet_mesh.content_key(TetVolume(CUBE * 2, CUBE_5, base.values)),
        tet_mesh.content_key(TetVolume(CUBE, CUBE_6, base.values)),
        tet_mesh.content_key(TetVolume(CUBE, CUBE_5, base.values.astype(np.float32))),
    }
    assert len(keys) == 4
    assert tet_mesh.content_key(cube_volume()) == tet_mesh.content_key(base)


# --------------------------------------------------------------------------------------------------
# Real data


def test_spx(shared_data):
    from volren.io import load_volume

    path = shared_data / "tets" / "spx.vtk"
    if not path.exists():
        pytest.skip(f"{SHARED_MISSING}: {path} not found")
    volume = load_volume(path, scalars="scalars")
    mesh = prepare_mesh(volume)
    assert (mesh.n_points, mesh.n_tets) == (2896, 12936)
    assert mesh.n_flat == 0 and mesh.n_nonmanifold_faces == 0 and mesh.n_reoriented == 0
    assert mesh.n_boundary == 2760
    check_adjacency(mesh)
    check_planes(mesh)
    check_boundary_outward(mesh)
    check_planes_shared(mesh)
    # The boundary surface is closed: every boundary edge is used once in each direction.
    tri = mesh.boundary_triangles
    edges = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    forward = {tuple(e) for e in edges.tolist()}
    assert len(forward) == len(edges) and all((b, a) in forward for a, b in forward)
