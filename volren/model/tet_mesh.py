"""A tetrahedral mesh prepared for cell-to-cell ray casting (Weiler et al.; Real-Time Volume Graphics, section 7.5.2).

`prepare_mesh(volume)` turns a `TetVolume` into a `PreparedMesh`: positively oriented cells, face
adjacency, outward face planes, per-cell gradients and the boundary faces where rays enter. It is
pure, vectorised numpy (O(m log m) in the number of cells m) and cached by content, in memory and
on disk, so reopening a file skips the work.

Conventions (shared with the ray-casting kernels):

- Face f of tet t is the face OPPOSITE vertex f, i.e. the vertices ``tets[t]`` without index f.
  `FACE_VERTICES[f]` lists the other three local indices in the order whose right-hand normal
  points out of a positively oriented tet.
- Points repeated with the same value are one point (`tet_repair.merged_duplicates`): ``tets``
  name the first copy, so faces between cells written with their own copies match. (Repeated
  cells never get here: `TetVolume` keeps one copy of each.)
- A tet is positively oriented when det[p1 - p0, p2 - p0, p3 - p0] > 0; inverted input cells get
  vertices 2 and 3 swapped.
- A tet is *flat* when it repeats a vertex or ``|V| <= FLAT_REL_TOL * l**3`` (l its longest
  edge): `volren.model.tet_repair.flat_cells`, the project's one flatness rule. Loading drops such
  cells (`repair_tets`) and renderers treat them as holes. Flat tets are kept here (the adjacency runs through them) with a
  zero gradient.
- ``neighbors[t, f]`` is the tet across face f and ``neighbor_faces[t, f]`` that face's index in
  the neighbour, so ``neighbors[neighbors[t, f], neighbor_faces[t, f]] == t``; both are -1 on the
  boundary. A face shared by more than two tets (non-manifold input) is boundary for all of them
  and counted in `n_nonmanifold_faces`; a face a degenerate tet shares with itself is boundary too.
- `PreparedMesh.planes` (`FacePlanes`) holds the plane of face f as a point p_a and a normal
  n = (p_b - p_a) x (p_c - p_a), where a < b < c are the face's global vertex ids, with sigma = +-1
  so that sigma n.(x - p_a) >= 0 inside. Both sides of an interior face compute n and p_a from the
  same sorted triple, so their planes are bit for bit the same with opposite sigma: rays clipped
  against them are partitioned exactly, with no cracks between cells. Flat and non-finite cells
  are not `usable`: renderers treat them as holes.
- ``gradients[t]`` is the gradient of the linear interpolant of `values` in tet t (Eq. 7.2:
  ``s(x) = values[tets[t, 0]] + gradients[t] . (x - points[tets[t, 0]])``); NaN when one of its
  vertex values is not finite (``nonfinite[t]``), which takes precedence over flatness.
"""

from __future__ import annotations

import functools
import hashlib
import os
import tempfile
import threading
from collections import OrderedDict
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError
from volren.model.tet_repair import flat_cells, merged_duplicates, signed_volumes
from volren.model.volume import TetVolume

#: Local vertex indices of face f (opposite vertex f), ordered so that the right-hand normal points
#: out of a positively oriented tet.
FACE_VERTICES = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]], dtype=np.int64)

#: Bumped whenever what `build_mesh` computes or what the cache file holds changes.
FORMAT_VERSION = 3

#: How many prepared meshes the process keeps (least recently used ones go first).
MEMORY_CACHE_ENTRIES = 4

#: Environment variable naming the on-disk cache folder (default ~/.cache/volren/meshes).
CACHE_ENV = "VOLREN_MESH_CACHE"

_EDGES = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))
_PACK_BITS = 21  # three vertex indices below 2**21 pack into one int64 face key


@dataclass(frozen=True, eq=False)
class PreparedMesh:
    """Everything a cell-to-cell ray caster reads, as read-only arrays (see the module docstring)."""

    points: NDArray[np.float64]  # (n, 3)
    values: NDArray[np.float64]  # (n,)
    tets: NDArray[np.int32]  # (m, 4), positively oriented (flat ones as given)
    neighbors: NDArray[np.int32]  # (m, 4), -1 on the boundary
    neighbor_faces: NDArray[np.int8]  # (m, 4), -1 on the boundary
    gradients: NDArray[np.float64]  # (m, 3)
    flat: NDArray[np.bool_]  # (m,)
    nonfinite: NDArray[np.bool_]  # (m,), some vertex value is NaN or Inf
    boundary_faces: NDArray[np.int32]  # (k, 2), (tet, face) pairs without neighbour, sorted
    boundary_triangles: NDArray[np.int32]  # (k, 3), point indices, right-hand normal outward
    n_nonmanifold_faces: int  # distinct faces shared by more than two tets
    n_reoriented: int  # input tets that were inverted and had vertices 2 and 3 swapped
    max_edge_length: float  # longest tet edge: the d axis of a 3D pre-integration table

    @property
    def n_points(self) -> int:
        return len(self.points)

    @property
    def n_tets(self) -> int:
        return len(self.tets)

    @property
    def n_boundary(self) -> int:
        """Faces without a neighbour (true boundary plus non-manifold and self-shared faces)."""
        return len(self.boundary_faces)

    @property
    def n_flat(self) -> int:
        return int(np.count_nonzero(self.flat))

    @functools.cached_property
    def bounds(self) -> tuple[float, float, float, float, float, float]:
        """(xmin, xmax, ymin, ymax, zmin, zmax) of the points, VTK's order (kept: renderers ask per frame)."""
        lo = self.points.min(axis=0)
        hi = self.points.max(axis=0)
        return (float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1]), float(lo[2]), float(hi[2]))

    @functools.cached_property
    def planes(self) -> FacePlanes:
        """The face planes the ray-casting kernels clip against (computed once per mesh, not stored
        on disk: they follow from the points and tets in O(m))."""
        return face_planes(self.points, self.tets, self.values, self.gradients, ~(self.flat | self.nonfinite))

    @property
    def nbytes(self) -> int:
        return sum(a.nbytes for a in self._arrays().values())

    def _arrays(self) -> dict[str, NDArray]:
        return {name: getattr(self, name) for name in _ARRAY_FIELDS}

    def __repr__(self) -> str:
        return (
            f"PreparedMesh({self.n_points} points, {self.n_tets} tets, {self.n_boundary} boundary faces, "
            f"{self.n_flat} flat, {self.n_nonmanifold_faces} non-manifold faces)"
        )


_ARRAY_FIELDS = (
    "points",
    "values",
    "tets",
    "neighbors",
    "neighbor_faces",
    "gradients",
    "flat",
    "nonfinite",
    "boundary_faces",
    "boundary_triangles",
)
#: What the cache file holds: everything but points and values, which come from the volume.
_STORED_ARRAYS = _ARRAY_FIELDS[2:]
_STORED_DTYPES = {
    "tets": np.int32,
    "neighbors": np.int32,
    "neighbor_faces": np.int8,
    "gradients": np.float64,
    "flat": np.bool_,
    "nonfinite": np.bool_,
    "boundary_faces": np.int32,
    "boundary_triangles": np.int32,
}


# --------------------------------------------------------------------------------------------------
# Building


def _sort3(a: NDArray, b: NDArray, c: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """Element-wise sort of three integer arrays (a three-comparator network)."""
    a, b = np.minimum(a, b), np.maximum(a, b)
    b, c = np.minimum(b, c), np.maximum(b, c)
    a, b = np.minimum(a, b), np.maximum(a, b)
    return a, b, c


def _match_faces(lo: NDArray, mid: NDArray, hi: NDArray, n_points: int) -> tuple[NDArray, NDArray, int]:
    """Pair the 4m faces (given by their sorted vertex triples) that are shared by exactly two tets.

    Returns the flat face indices of the pairs' first and second members and the number of distinct
    faces shared by more than two. Sorting the keys makes this O(m log m).
    """
    count = len(lo)
    if n_points <= 1 << _PACK_BITS:
        key = (lo << (2 * _PACK_BITS)) | (mid << _PACK_BITS) | hi
        order = np.argsort(key)
        sorted_key = key[order]
        new = np.empty(count, dtype=bool)
        new[0] = True
        np.not_equal(sorted_key[1:], sorted_key[:-1], out=new[1:])
    else:
        order = np.lexsort((hi, mid, lo))
        new = np.empty(count, dtype=bool)
        new[0] = True
        new[1:] = (
            (lo[order[1:]] != lo[order[:-1]])
            | (mid[order[1:]] != mid[order[:-1]])
            | (hi[order[1:]] != hi[order[:-1]])
        )
    starts = np.flatnonzero(new)
    lengths = np.diff(np.append(starts, count))
    pair_starts = starts[lengths == 2]
    first, second = order[pair_starts], order[pair_starts + 1]
    same_tet = first // 4 == second // 4  # a degenerate tet repeating one of its own faces
    return first[~same_tet], second[~same_tet], int(np.count_nonzero(lengths > 2))


def folded_cells(points: NDArray, tets: NDArray) -> NDArray[np.bool_]:
    """Which tetrahedra fold over a neighbour: they share a face whose two opposite vertices lie on
    the same side of its plane, so the two cells overlap (a tangled mesh).

    Why: reorienting an inverted cell fixes its vertex order, not where it lies, and a ray that
    walks from cell to cell across such a face runs backwards. The side of a cell's opposite vertex
    is its signed volume's sign times the parity of the face's vertex order in it (`FACE_VERTICES`)
    against the sorted order both cells share, so the test costs one determinant per cell and does
    not depend on vertex order (a mesh listed inverted throughout has no folds); the sign is exact
    for cells that are not flat, whose |6V| exceeds the determinant's rounding by far (one of zero
    volume folds nothing). Faces match
    by point index (merge repeated points first where they should match); a face of three cells
    matches none, and two copies of one cell are a repetition (`tet_repair.repeated_tets`)."""
    tets = np.asarray(tets, dtype=np.int64)
    folded = np.zeros(len(tets), dtype=bool)
    if len(tets) < 2:
        return folded
    faces = tets[:, FACE_VERTICES].reshape(-1, 3)  # row 4t + f
    a, b, c = faces[:, 0], faces[:, 1], faces[:, 2]
    first, second, _ = _match_faces(*_sort3(a, b, c), len(points))
    odd = (a > b) ^ (a > c) ^ (b > c)  # the face's order is an odd permutation of its sorted order
    volumes = np.repeat(signed_volumes(points, tets), 4)
    side = (volumes > 0) ^ odd
    fold = (side[first] == side[second]) & (tets[first // 4, first % 4] != tets[second // 4, second % 4])
    fold &= (volumes[first] != 0) & (volumes[second] != 0)  # a flat cell has no sides
    folded[first[fold] // 4] = True
    folded[second[fold] // 4] = True
    return folded


def build_mesh(points: NDArray, tets: NDArray, values: NDArray) -> PreparedMesh:
    """Prepare a mesh without any caching (`prepare_mesh` is the cached entry point)."""
    points = np.array(points, dtype=np.float64, order="C")
    values = np.array(values, dtype=np.float64, order="C")
    tets = np.array(tets, dtype=np.int64, order="C")
    n, m = len(points), len(tets)
    if points.shape != (n, 3) or tets.shape != (m, 4) or values.shape != (n,):
        shapes = f"points {points.shape}, tets {tets.shape}, values {values.shape}"
        raise VolrenError(f"mesh shapes do not fit: {shapes}")
    if m == 0 or n == 0:
        raise VolrenError(f"the mesh is empty ({n} points, {m} tetrahedra)")
    if 4 * m >= 2**31 or n >= 2**31:
        raise VolrenError(f"the mesh is too large for 32-bit indices ({n} points, {m} tetrahedra)")
    if tets.min() < 0 or tets.max() >= n:
        raise VolrenError(f"tetrahedra refer to points outside 0..{n - 1}")
    tets = merged_duplicates(points, values)[tets]

    # Orientation and flatness.
    p = points[tets]  # (m, 4, 3)
    e1, e2, e3 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]
    c23, c31, c12 = np.cross(e2, e3), np.cross(e3, e1), np.cross(e1, e2)
    det = np.einsum("ij,ij->i", e1, c23)  # 6 * signed volume
    longest_sq = np.zeros(m)
    repeated = np.zeros(m, dtype=bool)
    for a, b in _EDGES:
        d = p[:, a] - p[:, b]
        np.maximum(longest_sq, np.einsum("ij,ij->i", d, d), out=longest_sq)
        repeated |= tets[:, a] == tets[:, b]
    flat = flat_cells(det, np.sqrt(longest_sq), repeated)
    inverted = det < 0
    if inverted.any():
        tets[inverted, 2], tets[inverted, 3] = tets[inverted, 3], tets[inverted, 2]
        # Swapping vertices 2 and 3 swaps e2 and e3: det and c23 change sign, c31 <-> -c12.
        c23[inverted] *= -1.0
        c31[inverted], c12[inverted] = -c12[inverted], -c31[inverted]
        det[inverted] *= -1.0

    # Gradient of the linear interpolant: g = (d1 c23 + d2 c31 + d3 c12) / det, with
    # d_i = s_i - s_0 and c_jk = e_j x e_k (Cramer's rule for e_i . g = d_i).
    s = values[tets]
    nonfinite = ~np.all(np.isfinite(s), axis=1)
    ds = s[:, 1:] - s[:, :1]
    denominator = np.where(flat, 1.0, det)[:, None]
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        gradients = (ds[:, 0:1] * c23 + ds[:, 1:2] * c31 + ds[:, 2:3] * c12) / denominator
    gradients[flat] = 0.0
    gradients[nonfinite] = np.nan

    # Faces: vertex indices in outward order, and their sorted triples (the matching keys).
    faces = tets[:, FACE_VERTICES].reshape(-1, 3)  # (4m, 3), row 4t + f
    lo, mid, hi = _sort3(faces[:, 0], faces[:, 1], faces[:, 2])

    # Adjacency.
    first, second, n_nonmanifold = _match_faces(lo, mid, hi, n)
    neighbors = np.full(4 * m, -1, dtype=np.int32)
    neighbor_faces = np.full(4 * m, -1, dtype=np.int8)
    neighbors[first], neighbors[second] = second // 4, first // 4
    neighbor_faces[first], neighbor_faces[second] = second % 4, first % 4

    boundary = np.flatnonzero(neighbors == -1)
    boundary_faces = np.stack([boundary // 4, boundary % 4], axis=1).astype(np.int32)

    return _freeze(
        PreparedMesh(
            points=points,
            values=values,
            tets=tets.astype(np.int32),
            neighbors=neighbors.reshape(m, 4),
            neighbor_faces=neighbor_faces.reshape(m, 4),
            gradients=gradients,
            flat=flat,
            nonfinite=nonfinite,
            boundary_faces=boundary_faces,
            boundary_triangles=faces[boundary].astype(np.int32),
            n_nonmanifold_faces=n_nonmanifold,
            n_reoriented=int(np.count_nonzero(inverted)),
            max_edge_length=float(np.sqrt(longest_sq.max())),
        )
    )


@dataclass(frozen=True, eq=False)
class FacePlanes:
    """Per cell and face f (opposite vertex f): sigma n.(x - p_a) >= 0 inside (module docstring)."""

    normals: NDArray[np.float64]  # (m, 4, 3) n, not normalised (zero length for flat faces)
    anchors: NDArray[np.float64]  # (m, 4, 3) p_a, the face's vertex with the lowest global id
    sigma: NDArray[np.float64]  # (m, 4) +1 or -1
    values: NDArray[np.float64]  # (m, 4) the value at vertex f
    gradients: NDArray[np.float64]  # (m, 3) the constant gradient of the linear field
    usable: NDArray[np.bool_]  # (m,) neither flat nor with a non-finite vertex value


def face_planes(
    points: NDArray, tets: NDArray, values: NDArray, gradients: NDArray, usable: NDArray[np.bool_]
) -> FacePlanes:
    """`FacePlanes` of the cells `tets` (m, 4) of a mesh."""
    faces = tets[:, FACE_VERTICES]  # (m, 4, 3)
    lo, mid, hi = _sort3(faces[..., 0], faces[..., 1], faces[..., 2])
    anchors = points[lo]
    normals = np.cross(points[mid] - anchors, points[hi] - anchors)
    opposite = points[tets] - anchors  # vertex f minus the anchor of face f
    sigma = np.where(np.einsum("tfc,tfc->tf", normals, opposite) > 0.0, 1.0, -1.0)
    planes = FacePlanes(
        normals=normals,
        anchors=anchors,
        sigma=sigma,
        values=values[tets],
        gradients=np.ascontiguousarray(gradients),
        usable=np.ascontiguousarray(usable),
    )
    for name in ("normals", "anchors", "sigma", "values", "gradients", "usable"):
        getattr(planes, name).flags.writeable = False
    return planes


def _freeze(mesh: PreparedMesh) -> PreparedMesh:
    for array in mesh._arrays().values():
        array.flags.writeable = False
    return mesh


# --------------------------------------------------------------------------------------------------
# Caching


_memory: OrderedDict[str, PreparedMesh] = OrderedDict()
_lock = threading.RLock()


def content_key(volume: TetVolume) -> str:
    """sha256 (hex) of the format version and the volume's points, tets and values."""
    digest = hashlib.sha256(f"volren-tet-mesh-v{FORMAT_VERSION}".encode())
    for name in ("points", "tets", "values"):
        array = np.ascontiguousarray(getattr(volume, name))
        digest.update(f"|{name}:{array.dtype.str}:{array.shape}|".encode())
        digest.update(memoryview(array).cast("B"))  # type: ignore[arg-type]  # numpy types the buffer protocol from Python 3.12
    return digest.hexdigest()


def cache_dir() -> Path:
    """Where prepared meshes are stored: $VOLREN_MESH_CACHE, or ~/.cache/volren/meshes."""
    configured = os.environ.get(CACHE_ENV)
    return Path(configured).expanduser() if configured else Path.home() / ".cache" / "volren" / "meshes"


def cache_path(key: str) -> Path:
    return cache_dir() / f"{key}.npz"


def clear_memory_cache() -> None:
    """Forget the prepared meshes held in this process (the disk cache stays)."""
    with _lock:
        _memory.clear()


def _read_cached(path: Path, key: str, volume: TetVolume) -> PreparedMesh | None:
    """The mesh stored at `path` for `key`, or None when it is missing, corrupt or stale."""
    try:
        with np.load(path, allow_pickle=False) as data:
            if int(data["format_version"]) != FORMAT_VERSION or str(data["key"]) != key:
                return None
            arrays = {name: data[name] for name in _STORED_ARRAYS}
            counts = data["counts"]
            max_edge_length = float(data["max_edge_length"])
    except Exception:  # missing, truncated, not a zip, wrong contents: rebuild
        return None
    m, k = len(volume.tets), len(arrays["boundary_faces"])
    shapes = {
        "tets": (m, 4),
        "neighbors": (m, 4),
        "neighbor_faces": (m, 4),
        "gradients": (m, 3),
        "flat": (m,),
        "nonfinite": (m,),
        "boundary_faces": (k, 2),
        "boundary_triangles": (k, 3),
    }
    for name, array in arrays.items():
        if array.shape != shapes[name] or array.dtype != _STORED_DTYPES[name]:
            return None
    if counts.shape != (2,) or not np.issubdtype(counts.dtype, np.integer):
        return None
    return _freeze(
        PreparedMesh(
            points=np.array(volume.points, dtype=np.float64),
            values=np.array(volume.values, dtype=np.float64),
            **arrays,
            n_nonmanifold_faces=int(counts[0]),
            n_reoriented=int(counts[1]),
            max_edge_length=max_edge_length,
        )
    )


def _write_cached(path: Path, key: str, mesh: PreparedMesh) -> None:
    """Store `mesh` atomically (temp file + rename); failing to write is not an error."""
    tmp_name = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp_name = tempfile.mkstemp(prefix=f".{key[:16]}-", suffix=".tmp", dir=path.parent)
        with os.fdopen(fd, "wb") as handle:
            np.savez(
                handle,
                format_version=np.int64(FORMAT_VERSION),
                key=np.str_(key),
                counts=np.array([mesh.n_nonmanifold_faces, mesh.n_reoriented], dtype=np.int64),
                max_edge_length=np.float64(mesh.max_edge_length),
                **{name: getattr(mesh, name) for name in _STORED_ARRAYS},
            )
        os.replace(tmp_name, path)
        tmp_name = None
    except Exception:  # read-only or full disk: the mesh is still returned, just not stored
        pass
    finally:
        if tmp_name is not None:
            try:
                os.unlink(tmp_name)
            except OSError:
                pass


def prepare_mesh(volume: TetVolume, *, disk_cache: bool = True) -> PreparedMesh:
    """The prepared mesh of `volume`, from the in-process cache, the disk cache or built afresh.

    The cache key is the content (points, tets, values and `FORMAT_VERSION`), so two volumes with
    the same data share one entry. A cache file that cannot be read is rebuilt and rewritten.
    """
    if not isinstance(volume, TetVolume):
        raise VolrenError(f"prepare_mesh needs a tetrahedral volume, got {type(volume).__name__}")
    key = content_key(volume)
    with _lock:
        mesh = _memory.get(key)
        if mesh is not None:
            _memory.move_to_end(key)
            return mesh
        path = cache_path(key) if disk_cache else None
        mesh = _read_cached(path, key, volume) if path is not None else None
        if mesh is None:
            mesh = build_mesh(volume.points, volume.tets, volume.values)
            if path is not None:
                _write_cached(path, key, mesh)
        _memory[key] = mesh
        while len(_memory) > MEMORY_CACHE_ENTRIES:
            _memory.popitem(last=False)
        return mesh
