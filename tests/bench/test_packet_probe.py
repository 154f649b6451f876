"""`benchmarks.packet_probe`: its four loops draw the same rays alike, so their rates compare."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from benchmarks import packet_probe


def test_every_loop_takes_the_same_samples_and_draws_the_same_image():
    scene = packet_probe.Scene(n=24, rays_per_side=16)
    with tempfile.TemporaryDirectory() as folder:
        lib = packet_probe.build_c(Path(folder))  # None without a C compiler: the numba rows only
        rows = packet_probe.measure(scene, lib, repeats=1)
    names = [name for name, *_ in rows]
    assert names[:2] == ["numba, one ray", "numba, 8-ray packets"]
    assert ("C, one ray" in names) == (lib is not None)
    samples = {n for _, n, _, _ in rows}
    assert len(samples) == 1 and samples.pop() > 1000
    first = rows[0][3]
    assert first[:, 3].max() > 0.05  # the TF shows something: the comparison is not of empty images
    for _, _, _, image in rows[1:]:
        np.testing.assert_allclose(image, first, atol=1e-4)


def test_the_assembly_is_read_from_a_fresh_compile_not_numbas_cache():
    scene = packet_probe.Scene(n=8, rays_per_side=8)
    packet_probe.measure(scene, None, repeats=1)  # calls (and may load from the cache) both kernels
    text = packet_probe.assembly_of(packet_probe._packet)
    assert "ret" in text and "_packet" in text  # the kernel's own code, not a notice that inspection is off
