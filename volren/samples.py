"""The bundled sample volumes and transfer functions, and the code that makes them.

`data_samples/` in the repository holds what `write_samples` writes; installed copies without
that folder regenerate it into a cache folder on first use, so the samples are always the
output of this code (no data from elsewhere is shipped):

- ``marschner_lobb.vti``: the Marschner-Lobb test signal (1994) on a 41^3 grid over [-1, 1]^3,
  float32: a classic test of reconstruction and sampling accuracy.
- ``phantom_ct.vti``: a CT-like 3D Shepp-Logan head phantom, 64^3 int16 in Hounsfield-like units,
  with ``phantom_ct.labels.vti`` (its ellipsoids as labels: skull, brain, ventricles, a cyst and
  nodules) and their names and colours in ``phantom_ct.labels.json``.
- ``hollow_cylinder.vtu``: a tetrahedral mesh of a hollow cylinder (non-convex) carrying an
  analytic field, for the tetrahedral renderers.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from volren.model.colormaps import VIRIDIS, color_stops
from volren.model.labels import PALETTE, LabelMap
from volren.model.tet_repair import repair_tets
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import TetVolume, UniformVolume

SAMPLES = {
    "marschner_lobb": ("marschner_lobb.vti", "marschner_lobb.tf.json"),
    "phantom_ct": ("phantom_ct.vti", "phantom_ct.tf.json"),
    "hollow_cylinder": ("hollow_cylinder.vtu", "hollow_cylinder.tf.json"),
}
#: Samples with a segmentation: (label volume file, label names and colours file).
SAMPLE_LABELS = {"phantom_ct": ("phantom_ct.labels.vti", "phantom_ct.labels.json")}
REPO_SAMPLES = Path(__file__).resolve().parent.parent / "data_samples"
#: The phantom's labels, one per ellipsoid (0 is the air around it).
PHANTOM_LABELS = ("skull", "brain", "ventricle 1", "ventricle 2", "cyst", "nodule 1", "nodule 2", "nodule 3",
                  "nodule 4", "nodule 5")  # fmt: skip


def marschner_lobb(n: int = 41, f_m: float = 6.0, alpha: float = 0.25) -> UniformVolume:
    """rho(x, y, z) = (1 - sin(pi z / 2) + alpha (1 + cos(2 pi f_m cos(pi r / 2)))) / (2 (1 + alpha))."""
    t = np.linspace(-1.0, 1.0, n)
    z, y, x = np.meshgrid(t, t, t, indexing="ij")
    r = np.sqrt(x * x + y * y)
    rho_r = np.cos(2.0 * np.pi * f_m * np.cos(np.pi * r / 2.0))
    values = (1.0 - np.sin(np.pi * z / 2.0) + alpha * (1.0 + rho_r)) / (2.0 * (1.0 + alpha))
    step = 2.0 / (n - 1)
    return UniformVolume(values.astype(np.float32), (step,) * 3, (-1.0,) * 3, name="marschner_lobb")


# Shepp-Logan 3D ellipsoids (Kak & Slaney's 3D extension): centre, semi-axes, rotation about z
# (degrees), density change. Densities are scaled to Hounsfield-like units below.
_ELLIPSOIDS = [
    ((0.0, 0.0, 0.0), (0.69, 0.92, 0.90), 0.0, 2.0),
    ((0.0, 0.0, 0.0), (0.6624, 0.874, 0.88), 0.0, -0.98),
    ((-0.22, 0.0, -0.25), (0.41, 0.16, 0.21), 108.0, -0.02),
    ((0.22, 0.0, -0.25), (0.31, 0.11, 0.22), 72.0, -0.02),
    ((0.0, 0.35, -0.25), (0.21, 0.25, 0.50), 0.0, 0.01),
    ((0.0, 0.1, -0.25), (0.046, 0.046, 0.046), 0.0, 0.01),
    ((-0.08, -0.65, -0.25), (0.046, 0.023, 0.02), 0.0, 0.01),
    ((0.06, -0.65, -0.25), (0.046, 0.023, 0.02), 90.0, 0.01),
    ((0.06, -0.105, 0.625), (0.056, 0.04, 0.1), 90.0, 0.02),
    ((0.0, 0.1, 0.625), (0.056, 0.056, 0.1), 0.0, -0.02),
]


def shepp_logan_ct(n: int = 64) -> UniformVolume:
    """A head phantom: air -1000, soft tissue about 0..40, skull about +1000 (int16)."""
    t = np.linspace(-1.0, 1.0, n)
    z, y, x = np.meshgrid(t, t, t, indexing="ij")
    density = np.zeros_like(x)
    for (cx, cy, cz), (a, b, c), angle, value in _ELLIPSOIDS:
        phi = np.radians(angle)
        xr = (x - cx) * np.cos(phi) + (y - cy) * np.sin(phi)
        yr = -(x - cx) * np.sin(phi) + (y - cy) * np.cos(phi)
        inside = (xr / a) ** 2 + (yr / b) ** 2 + ((z - cz) / c) ** 2 <= 1.0
        density[inside] += value
    # density 0 -> air, 1.02 -> soft tissue, 2.0 -> bone; map piecewise-linearly to HU.
    hu = np.interp(density, [0.0, 1.0, 1.05, 2.0], [-1000.0, -20.0, 60.0, 1000.0])
    step = 2.0 / (n - 1)
    return UniformVolume(np.round(hu).astype(np.int16), (step,) * 3, (-1.0,) * 3, name="phantom_ct")


def shepp_logan_labels(n: int = 64) -> LabelMap:
    """The phantom's segmentation: at each grid point the last of its ellipsoids that holds it
    (ellipsoid k is label k + 1, named in `PHANTOM_LABELS`; the skull is the first ellipsoid less
    the second), 0 outside, coloured from the label palette."""
    t = np.linspace(-1.0, 1.0, n)
    z, y, x = np.meshgrid(t, t, t, indexing="ij")
    labels = np.zeros(x.shape, np.uint8)
    for k, ((cx, cy, cz), (a, b, c), angle, _) in enumerate(_ELLIPSOIDS):
        phi = np.radians(angle)
        xr = (x - cx) * np.cos(phi) + (y - cy) * np.sin(phi)
        yr = -(x - cx) * np.sin(phi) + (y - cy) * np.cos(phi)
        labels[(xr / a) ** 2 + (yr / b) ** 2 + ((z - cz) / c) ** 2 <= 1.0] = k + 1
    names = dict(enumerate(PHANTOM_LABELS, start=1))
    colors = {label: PALETTE[label - 1] for label in names}
    return LabelMap(labels, names, colors, name="phantom_ct.labels")


def hollow_cylinder(n_r: int = 5, n_theta: int = 32, n_z: int = 12) -> TetVolume:
    """Tetrahedra filling 0.5 <= r <= 1, 0 <= z <= 2, with f = r cos(3 theta) + z / 2.

    Each hexahedron of the (r, theta, z) lattice is split into 6 tetrahedra along its main
    diagonal, a split that is conforming between neighbours.
    """
    r = np.linspace(0.5, 1.0, n_r)
    theta = np.linspace(0.0, 2.0 * np.pi, n_theta, endpoint=False)
    z = np.linspace(0.0, 2.0, n_z)
    rr, tt, zz = np.meshgrid(r, theta, z, indexing="ij")
    points = np.stack([rr * np.cos(tt), rr * np.sin(tt), zz], axis=-1).reshape(-1, 3)
    index = np.arange(rr.size).reshape(rr.shape)
    tets = []
    # corner (a, b, c) of a cell, theta wrapping around
    for i in range(n_r - 1):
        for j in range(n_theta):
            jn = (j + 1) % n_theta
            for k in range(n_z - 1):
                v = {
                    (a, b, c): index[i + a, (j, jn)[b], k + c] for a in (0, 1) for b in (0, 1) for c in (0, 1)
                }
                for path in _KUHN_PATHS:
                    tets.append([v[p] for p in path])
    values = rr * np.cos(3.0 * tt) + zz / 2.0
    repaired = repair_tets(points, np.array(tets))
    return TetVolume(points, repaired.tets, values.reshape(-1), name="hollow_cylinder")


# The 6 Kuhn simplices of a cube: paths from (0,0,0) to (1,1,1) along the axes in every order.
_KUHN_PATHS = []
for _order in ((0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)):
    _corner = [0, 0, 0]
    _path = [tuple(_corner)]
    for _axis in _order:
        _corner[_axis] = 1
        _path.append(tuple(_corner))
    _KUHN_PATHS.append(_path)


def sample_transfer_functions() -> dict[str, TransferFunction1D]:
    """Transfer functions that show each sample well."""
    # A soft shell around the 0.5 isosurface shows the signal's rings, the classic ML view.
    ml = TransferFunction1D(
        color_stops(VIRIDIS, 0.0, 1.0), [[0.0, 0.0], [0.4, 0.0], [0.5, 0.7], [0.6, 0.0], [1.0, 0.0]], 0.05
    )
    bone = [
        [-1000.0, 0.0, 0.0, 0.0],
        [20.0, 0.75, 0.25, 0.15],
        [44.0, 1.0, 0.7, 0.35],
        [400.0, 1.0, 0.94, 0.85],
        [1000.0, 1.0, 1.0, 1.0],
    ]
    # Brain (about 12 HU) transparent, the denser inner ellipsoids (28-44 HU) bright, the skull faint.
    ct = TransferFunction1D(
        bone,
        [[-1000.0, 0.0], [16.0, 0.0], [28.0, 0.25], [44.0, 0.5], [80.0, 0.02], [1000.0, 0.08]],
        0.03,
    )
    cool_warm = [[-1.0, 0.23, 0.299, 0.754], [0.5, 0.865, 0.865, 0.865], [2.0, 0.706, 0.016, 0.15]]
    cyl = TransferFunction1D(cool_warm, [[-1.0, 0.3], [0.3, 0.02], [0.7, 0.02], [2.0, 0.6]], 0.1)
    return {"marschner_lobb": ml, "phantom_ct": ct, "hollow_cylinder": cyl}


def sample_volumes() -> dict[str, UniformVolume | TetVolume]:
    return {
        "marschner_lobb": marschner_lobb(),
        "phantom_ct": shepp_logan_ct(),
        "hollow_cylinder": hollow_cylinder(),
    }


def write_samples(folder: str | Path) -> list[Path]:
    """Write every sample volume and its transfer function into `folder`."""
    from volren.io import save_transfer_function
    from volren.io.volume_writer import save_volume

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    tfs = sample_transfer_functions()
    for name, volume in sample_volumes().items():
        volume_file, tf_file = SAMPLES[name]
        save_volume(volume, folder / volume_file)
        save_transfer_function(tfs[name], folder / tf_file)
        written += [folder / volume_file, folder / tf_file]
    for name, (labels_file, info_file) in SAMPLE_LABELS.items():
        labels = shepp_logan_labels()
        volume = sample_volumes()[name]
        assert isinstance(volume, UniformVolume)
        save_volume(
            UniformVolume(labels.values, volume.spacing, volume.origin, name=labels.name),
            folder / labels_file,
        )
        entries = [
            {"value": v, "name": labels.names[v], "color": list(labels.colors[v])}
            for v in sorted(labels.names)
        ]
        (folder / info_file).write_text(json.dumps({"version": 1, "labels": entries}, indent=1) + "\n")
        written += [folder / labels_file, folder / info_file]
    return written


def _sample_files() -> list[str]:
    return [f for pair in (*SAMPLES.values(), *SAMPLE_LABELS.values()) for f in pair]


def samples_folder() -> Path:
    """The folder with the sample files: the repository's, else a generated cache copy."""
    if all((REPO_SAMPLES / f).exists() for f in _sample_files()):
        return REPO_SAMPLES
    cache = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "volren" / "data_samples"
    if not all((cache / f).exists() for f in _sample_files()):
        write_samples(cache)
    return cache


def sample_paths(name: str) -> tuple[Path, Path]:
    """(volume file, transfer-function file) of the sample `name`."""
    if name not in SAMPLES:
        raise KeyError(f"unknown sample {name!r}; choose one of {', '.join(SAMPLES)}")
    folder = samples_folder()
    volume_file, tf_file = SAMPLES[name]
    return folder / volume_file, folder / tf_file


def main(argv: list[str] | None = None) -> None:
    """python -m volren.samples [FOLDER]: regenerate the samples (default: data_samples/)."""
    import sys

    args = sys.argv[1:] if argv is None else argv
    for path in write_samples(args[0] if args else REPO_SAMPLES):
        print(f"{path} ({path.stat().st_size / 1024:.0f} KiB)")


if __name__ == "__main__":
    main()


__all__ = [
    "hollow_cylinder",
    "marschner_lobb",
    "sample_paths",
    "sample_transfer_functions",
    "sample_volumes",
    "samples_folder",
    "shepp_logan_ct",
    "shepp_logan_labels",
    "write_samples",
]
