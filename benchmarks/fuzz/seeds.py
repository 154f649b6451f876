"""Valid small volumes in every format volren reads: the seeds that the fuzz corpus mutates.

Each seed is deterministic (the same bytes on every machine with the same VTK): VTK's writers for
the VTK formats, MetaImage and NIfTI, and volren's own few lines for NRRD, SLC, DICOM and
legacy meshes, whose headers the mutations then rewrite field by field.
"""

from __future__ import annotations

import gzip
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from volren.testing.dicom_series import slice_bytes

SHAPE = (8, 7, 6)  # nx, ny, nz: small enough that every case reads in milliseconds
SPACING = (0.5, 0.75, 1.25)


@dataclass(frozen=True)
class Seed:
    """A valid input: its files, the path `volren render` is given, and flags it needs."""

    name: str
    files: dict[str, bytes]
    target: str
    flags: tuple[str, ...] = ()
    kind: str = "grid"  # or "mesh"


def grid_values() -> NDArray[np.int16]:
    """values[k, j, i]: a ball of high values in a ramp, so that every renderer draws something."""
    nx, ny, nz = SHAPE
    k, j, i = np.meshgrid(np.arange(nz), np.arange(ny), np.arange(nx), indexing="ij")
    r = np.sqrt((i - nx / 2) ** 2 + (j - ny / 2) ** 2 + (k - nz / 2) ** 2)
    return (100 * i + np.where(r < 2.5, 1500, 0)).astype(np.int16)


def mesh() -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.float32]]:
    """A 3x3x3-point lattice split into 40 tetrahedra (five per cube), with a value per point."""
    lattice = np.array([(x, y, z) for z in range(3) for y in range(3) for x in range(3)], float)
    five = ((0, 1, 3, 5), (0, 3, 2, 6), (0, 5, 4, 6), (3, 5, 6, 7), (0, 3, 5, 6))
    tets = []
    for cz in range(2):
        for cy in range(2):
            for cx in range(2):
                corner = [
                    (cx + dx) + 3 * (cy + dy) + 9 * (cz + dz)
                    for dz in (0, 1)
                    for dy in (0, 1)
                    for dx in (0, 1)
                ]
                tets += [[corner[v] for v in t] for t in five]
    values = (lattice[:, 0] + 2 * lattice[:, 1] + 3 * lattice[:, 2]).astype(np.float32)
    return lattice, np.array(tets, np.int64), values


def _written(write: Callable[[Path], None], name: str) -> bytes:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / name
        write(path)
        return path.read_bytes()


def _image():
    import pyvista as pv

    img = pv.ImageData(dimensions=SHAPE, spacing=SPACING, origin=(1.0, -2.0, 0.5))
    img.point_data["density"] = grid_values().reshape(-1)
    return img


def _vtk_seeds() -> list[Seed]:
    import pyvista as pv
    import vtk

    img = _image()
    points, tets, values = mesh()
    cells = np.hstack([np.full((len(tets), 1), 4), tets]).reshape(-1)
    grid = pv.UnstructuredGrid(cells, np.full(len(tets), 10, np.uint8), points)
    grid.point_data["pressure"] = values

    def meta(path: Path, compress: bool) -> None:
        writer = vtk.vtkMetaImageWriter()
        writer.SetInputData(img)
        writer.SetFileName(str(path))
        writer.SetCompression(compress)
        writer.Write()

    def meta_pair(compress: bool) -> dict[str, bytes]:
        with tempfile.TemporaryDirectory() as tmp:
            meta(Path(tmp) / "head.mhd", compress)
            return {p.name: p.read_bytes() for p in sorted(Path(tmp).iterdir())}

    return [
        Seed("vti-raw", {"v.vti": _written(lambda p: img.save(p, compression=None), "v.vti")}, "v.vti"),
        Seed("vti-zlib", {"v.vti": _written(lambda p: img.save(p), "v.vti")}, "v.vti"),
        Seed("vti-ascii", {"v.vti": _written(lambda p: img.save(p, binary=False), "v.vti")}, "v.vti"),
        Seed("legacy-binary", {"v.vtk": _written(lambda p: img.save(p, binary=True), "v.vtk")}, "v.vtk"),
        Seed("legacy-ascii", {"v.vtk": _written(lambda p: img.save(p, binary=False), "v.vtk")}, "v.vtk"),
        Seed("vtu-binary", {"m.vtu": _written(lambda p: grid.save(p), "m.vtu")}, "m.vtu", kind="mesh"),
        Seed(
            "vtu-ascii",
            {"m.vtu": _written(lambda p: grid.save(p, binary=False), "m.vtu")},
            "m.vtu",
            kind="mesh",
        ),
        Seed(
            "legacy-mesh-51",
            {"m.vtk": _written(lambda p: grid.save(p, binary=True), "m.vtk")},
            "m.vtk",
            kind="mesh",
        ),  # fmt: skip
        Seed("mhd", meta_pair(False), "head.mhd"),
        Seed("mha-zlib", {"v.mha": _written(lambda p: meta(p, True), "v.mha")}, "v.mha"),
        Seed("mha-raw", {"v.mha": _written(lambda p: meta(p, False), "v.mha")}, "v.mha"),
        Seed("nii", {"v.nii": _written(lambda p: img.save(p), "v.nii")}, "v.nii"),
        Seed("nii-gz", {"v.nii.gz": _written(lambda p: img.save(p), "v.nii.gz")}, "v.nii.gz"),
    ]


def nrrd_header(encoding: str = "raw", data_file: str | None = None) -> str:
    nx, ny, nz = SHAPE
    lines = [
        "NRRD0004",
        "type: short",
        "dimension: 3",
        "space: left-posterior-superior",
        f"sizes: {nx} {ny} {nz}",
        f"space directions: ({SPACING[0]},0,0) (0,{SPACING[1]},0) (0,0,{SPACING[2]})",
        "space origin: (1,-2,0.5)",
        "kinds: domain domain domain",
        "endian: little",
        f"encoding: {encoding}",
    ]
    if data_file:
        lines.append(f"data file: {data_file}")
    return "\n".join(lines) + "\n"


def _nrrd_seeds() -> list[Seed]:
    data = grid_values().astype("<i2").tobytes()
    text = " ".join(str(v) for v in grid_values().reshape(-1)).encode()
    return [
        Seed("nrrd-raw", {"v.nrrd": (nrrd_header() + "\n").encode() + data}, "v.nrrd"),
        Seed("nrrd-gzip", {"v.nrrd": (nrrd_header("gzip") + "\n").encode() + gzip.compress(data, mtime=0)}, "v.nrrd"),
        Seed("nrrd-ascii", {"v.nrrd": (nrrd_header("ascii") + "\n").encode() + text + b"\n"}, "v.nrrd"),
        Seed("nhdr", {"v.nhdr": nrrd_header("raw", "v.raw").encode(), "v.raw": data}, "v.nhdr"),
    ]  # fmt: skip


def rle(row: bytes) -> bytes:
    """SLC's run-length code: a run byte (count | 0x80 for literal bytes), then the bytes; 0 ends."""
    out = bytearray()
    for start in range(0, len(row), 127):
        chunk = row[start : start + 127]
        out += bytes([0x80 | len(chunk)]) + chunk
    return bytes(out + b"\0")


def slc_bytes(values: NDArray[np.uint8], compressed: bool) -> bytes:
    """An SLC file of uint8 values[k, j, i] with a 2x2 icon (RLE slices when `compressed`)."""
    nz, ny, nx = values.shape
    head = f"11111\n{nx} {ny} {nz} 8\n{SPACING[0]} {SPACING[1]} {SPACING[2]}\n1 6 0 {int(compressed)}\n2 2 X"
    out = bytearray(head.encode()) + bytes(12)  # the icon: three 2x2 planes
    for plane in values:
        raw = np.ascontiguousarray(plane, np.uint8).tobytes()
        out += f"{len(rle(raw))} X".encode() + rle(raw) if compressed else raw
    return bytes(out)


def _slc_seeds() -> list[Seed]:
    values = (grid_values() // 8).clip(0, 255).astype(np.uint8)
    return [
        Seed("slc-rle", {"v.slc": slc_bytes(values, True)}, "v.slc"),
        Seed("slc-raw", {"v.slc": slc_bytes(values, False)}, "v.slc"),
    ]


def dicom_files(values: NDArray) -> dict[str, bytes]:
    return {
        f"series/s{k:02d}.dcm": slice_bytes(plane, k, SPACING, (1.0, -2.0, 0.5 + k * SPACING[2]))
        for k, plane in enumerate(values)
    }


def legacy_mesh_text(points: NDArray, tets: NDArray, values: NDArray) -> str:
    """A legacy (version 3.0) ASCII unstructured grid: the layout hand-written meshes use."""
    lines = ["# vtk DataFile Version 3.0", "mesh", "ASCII", "DATASET UNSTRUCTURED_GRID"]
    lines.append(f"POINTS {len(points)} float")
    lines += [" ".join(f"{c:g}" for c in p) for p in points]
    lines.append(f"CELLS {len(tets)} {5 * len(tets)}")
    lines += ["4 " + " ".join(str(int(v)) for v in t) for t in tets]
    lines.append(f"CELL_TYPES {len(tets)}")
    lines += ["10"] * len(tets)
    lines += [f"POINT_DATA {len(points)}", "SCALARS pressure float 1", "LOOKUP_TABLE default"]
    lines += [f"{v:g}" for v in values]
    return "\n".join(lines) + "\n"


def seeds() -> list[Seed]:
    """Every seed, in a fixed order."""
    points, tets, values = mesh()
    raw = grid_values().astype("<i2").tobytes()
    shape = ",".join(str(n) for n in SHAPE)
    return [
        *_vtk_seeds(),
        *_nrrd_seeds(),
        *_slc_seeds(),
        Seed("dicom", dicom_files(grid_values()), "series"),
        Seed("raw", {"v.raw": raw}, "v.raw", ("--raw-shape", shape, "--raw-dtype", "int16")),
        Seed(
            "legacy-mesh-30", {"m.vtk": legacy_mesh_text(points, tets, values).encode()}, "m.vtk", kind="mesh"
        ),
    ]
