"""The numba face planes equal the numpy path's (face_planes then pack_planes), and the two cells
of every shared face get exactly opposite planes."""

import numpy as np
import pyvista as pv

from volren.kernels.tet_planes import packed_face_planes
from volren.model.tet_mesh import face_planes
from volren.renderers.tetra.traversal import pack_planes


def _mesh(flat: bool = True):
    grid = pv.ImageData(dimensions=(5, 4, 4)).triangulate()
    rng = np.random.default_rng(3)
    points = np.asarray(grid.points, dtype=np.float64) + rng.normal(0, 0.05, (grid.n_points, 3))
    tets = np.asarray(grid.cells_dict[pv.CellType.TETRA], dtype=np.int64)
    tets[::7] = tets[::7][:, [1, 0, 2, 3]]  # both orientations
    if flat:  # a cell collapsed onto a vertex: zero planes on its collapsed faces (its neighbours invert)
        points[tets[5, 3]] = points[tets[5, 0]]
    return points, tets


def test_the_planes_equal_the_numpy_path() -> None:
    points, tets = _mesh()
    values = np.zeros(len(points))
    p = face_planes(points, tets, values, np.zeros((len(tets), 3)), np.ones(len(tets), bool))
    expected = pack_planes(p.normals, p.anchors, p.sigma)
    got = packed_face_planes(points, tets)
    np.testing.assert_allclose(got, expected, rtol=1e-14, atol=1e-14)
    assert np.count_nonzero(np.all(got[..., :3] == 0, axis=-1)) >= 1  # the flat cell's faces


def test_shared_faces_get_exactly_opposite_planes() -> None:
    points, tets = _mesh(flat=False)
    got = packed_face_planes(points, tets)
    keys = {}
    shared = 0
    for t, tet in enumerate(tets):
        for f in range(4):
            key = tuple(sorted(np.delete(tet, f)))
            if key in keys:
                u, g = keys[key]
                if np.any(got[t, f, :3] != 0):
                    np.testing.assert_array_equal(got[t, f], -got[u, g])
                    shared += 1
            else:
                keys[key] = (t, f)
    assert shared > 50
