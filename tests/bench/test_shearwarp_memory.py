"""`benchmarks.shearwarp_memory`: the classified volume's sizes add up and the edit changes the support."""

from __future__ import annotations

import numpy as np
import pytest

from volren.model import TransferFunction1D, UniformVolume

pytest.importorskip("volren_shearwarp")
from benchmarks import shearwarp_memory  # noqa: E402


@pytest.mark.parametrize("dtype, extra_copies", [(np.uint8, 2), (np.float64, 3)])
def test_the_copies_memory_their_ranges_and_runs_are_counted(dtype, extra_copies):
    """8-bit data keeps its type, so the copy along z is the volume itself; float64 data gets three
    float32 copies."""
    z, y, x = np.mgrid[0:9, 0:10, 0:11]
    volume = UniformVolume((x + y + z).astype(dtype))
    tf = TransferFunction1D([[0, 1, 1, 1], [28, 1, 1, 1]], [[10, 0.0], [12, 0.5], [14, 0.0]])
    assert shearwarp_memory._support(volume, tf).digest != shearwarp_memory._support(
        volume, shearwarp_memory._edited(tf, volume)).digest  # fmt: skip
    m = shearwarp_memory._measure(volume, tf, extent=1)
    itemsize = 1 if dtype == np.uint8 else 4
    assert m["copies"] == extra_copies * itemsize * volume.values.size
    # two bytes a block; at extent 1 an axis has (n_c - 1) slabs of n_b x n_a blocks
    n = volume.values.shape
    expected = sum(2 * (n[c] - 1) * n[(c + 1) % 3] * n[(c + 2) % 3] for c in range(3))
    assert m["ranges"] == expected
    assert m["runs"] > 0
    assert all(len(m[k]) == 3 and min(m[k]) >= 0 for k in ("copy_ms", "ranges_ms", "rebuild_ms"))
