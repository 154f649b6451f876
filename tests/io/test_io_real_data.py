"""Every real dataset in ../shared/data loads as MANIFEST.md describes it."""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv

from volren.errors import VolrenError, VolrenWarning
from volren.io import load_volume
from volren.model.volume import TetVolume, UniformVolume

# file: (dims, spacing, dtype)  -- MANIFEST.md
UNIFORM = {
    "bonsai.vti": ((256, 256, 256), (1, 1, 1), np.uint8),
    "engine.vti": ((256, 256, 128), (1, 1, 1), np.uint8),
    "aneurism.vti": ((256, 256, 256), (1, 1, 1), np.uint8),
    "ironProt.vtk": ((68, 68, 68), (1, 1, 1), np.uint8),
    "HeadMRVolume.mhd": ((48, 62, 42), (4, 4, 4), np.uint8),
    "neghip.slc": ((66, 66, 66), (1, 1, 1), np.uint8),
    "iguana.vti": ((210, 256, 179), (0.1018, 0.1018, 0.1018), np.uint8),
    "hydrogen.vti": ((64, 64, 64), (1, 1, 1), np.float32),
    "fuel.vti": ((64, 33, 32), (1, 1, 1), np.uint8),
}
# file: (scalars, points, tets in the file, value range or None)
TETS = {
    "spx.vtk": ("scalars", 2896, 12936, (0.0, 2.254)),
    "post_small_tets.vtk": ("Pressure", 2288, 8750, None),
    "bluntfin_tets.vtu": ("Density", 40960, 187395, (0.193, 4.977)),
    "oxygen_post_tets.vtu": ("VelocityMagnitude", 109744, 513375, (0.0, 1.391)),
    "cth_tets.vtu": ("Material Fraction", 274625, 1310720, (0.0, 1.0)),
}
BLUNTFIN_ZERO_VOLUME = 77


def test_manifest_lists_every_file(shared_data):
    uniform = {p.name for p in (shared_data / "uniform").iterdir() if p.suffix != ".raw"}
    tets = {p.name for p in (shared_data / "tets").iterdir()}
    assert uniform == set(UNIFORM)
    assert tets == set(TETS)


@pytest.mark.parametrize("name", sorted(UNIFORM))
def test_uniform_files(shared_data, name):
    dims, spacing, dtype = UNIFORM[name]
    path = shared_data / "uniform" / name
    volume = load_volume(path)
    assert isinstance(volume, UniformVolume)
    assert volume.name == name
    assert volume.dimensions == dims
    assert volume.spacing == pytest.approx(spacing)
    assert volume.values.dtype == dtype
    # values and their [k, j, i] order agree with an independent pyvista read
    reference = pv.read(path)
    flat = np.asarray(reference.active_scalars)
    assert volume.value_range == (float(flat.min()), float(flat.max()))
    nx, ny, nz = dims
    for i, j, k in [(0, 0, 0), (nx - 1, 0, 0), (1, ny - 2, nz - 1), (nx // 2, ny // 3, nz // 2)]:
        assert volume.values[k, j, i] == flat[i + nx * (j + ny * k)]
    assert volume.notes == ()


@pytest.mark.parametrize("name", sorted(set(TETS) - {"bluntfin_tets.vtu"}))
def test_tet_files(shared_data, name):
    scalars, n_points, n_tets, value_range = TETS[name]
    volume = load_volume(shared_data / "tets" / name)  # default array: the active (else first) one
    assert isinstance(volume, TetVolume)
    assert volume.name == name
    assert len(volume.points) == n_points
    assert len(volume.tets) == n_tets
    assert volume.values.dtype == np.float32
    reference = pv.read(shared_data / "tets" / name).point_data[scalars]
    np.testing.assert_array_equal(volume.values, reference)
    if value_range:
        assert volume.value_range == pytest.approx(value_range, abs=1e-3)
    assert volume.notes == ()


def test_bluntfin_drops_its_77_zero_volume_tets(shared_data):
    with pytest.warns(
        VolrenWarning, match=f"bluntfin_tets.vtu: dropped {BLUNTFIN_ZERO_VOLUME} zero-volume tetrahedra$"
    ):
        volume = load_volume(shared_data / "tets" / "bluntfin_tets.vtu", "Density")
    assert len(volume.tets) == TETS["bluntfin_tets.vtu"][2] - BLUNTFIN_ZERO_VOLUME
    assert volume.notes == (f"bluntfin_tets.vtu: dropped {BLUNTFIN_ZERO_VOLUME} zero-volume tetrahedra",)
    assert volume.value_range == pytest.approx((0.193, 4.977), abs=1e-3)


def test_other_arrays_of_a_real_mesh(shared_data):
    path = shared_data / "tets" / "bluntfin_tets.vtu"
    with pytest.warns(VolrenWarning, match="dropped 77 zero-volume"):
        momentum = load_volume(path, "Momentum:y")
    np.testing.assert_array_equal(momentum.values, pv.read(path).point_data["Momentum"][:, 1])
    available = ("'Density', 'Momentum:magnitude', 'Momentum:x', 'Momentum:y', 'Momentum:z', 'StagnationEnergy', "
                 "'VelocityMagnitude'")  # fmt: skip
    with pytest.raises(VolrenError, match=f"no array named 'Pressure'; available: {available}$"):
        load_volume(path, "Pressure")
    with pytest.warns(VolrenWarning, match="dropped 77 zero-volume"):
        energy = load_volume(path, "StagnationEnergy")
    reference = pv.read(path).point_data["StagnationEnergy"]
    np.testing.assert_array_equal(energy.values, reference)
