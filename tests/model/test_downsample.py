"""`volren.model.downsample`: bounds kept, linear data exact, NaN kept transparent, bad factors refused."""

import numpy as np
import pytest

from volren.errors import VolrenError
from volren.model import UniformVolume
from volren.model.downsample import downsample


def _ramp(shape_zyx, spacing=(1.0, 1.0, 1.0), origin=(0.0, 0.0, 0.0)):
    z, y, x = np.meshgrid(
        *(np.arange(n) * s for n, s in zip(shape_zyx, spacing[::-1], strict=True)), indexing="ij"
    )
    return UniformVolume(
        (0.5 * x - 2.0 * y + 3.0 * z + 7.0).astype(np.float32), spacing=spacing, origin=origin
    )


@pytest.mark.parametrize("factor", [2, 4, 8])
@pytest.mark.parametrize("shape", [(17, 20, 33), (2, 9, 64), (65, 3, 10)])
def test_bounds_kept_and_linear_data_exact(factor, shape):
    vol = _ramp(shape, spacing=(0.5, 2.0, 1.5), origin=(3.0, -1.0, 2.0))
    coarse = downsample(vol, factor)
    assert np.allclose(coarse.bounds, vol.bounds)
    for n, m in zip(vol.values.shape, coarse.values.shape, strict=True):
        assert m >= 2 and m <= max(2, n)
    # the coarse samples lie on the same linear function of world position
    nz, ny, nx = coarse.values.shape
    sx, sy, sz = coarse.spacing
    z, y, x = np.meshgrid(np.arange(nz) * sz, np.arange(ny) * sy, np.arange(nx) * sx, indexing="ij")
    np.testing.assert_allclose(coarse.values, 0.5 * x - 2.0 * y + 3.0 * z + 7.0, rtol=0, atol=2e-4)


def test_factor_one_is_the_volume_and_halving_counts():
    vol = UniformVolume(np.zeros((5, 256, 257), np.uint8))
    assert downsample(vol, 1) is vol
    coarse = downsample(vol, 2)
    assert coarse.values.shape == (3, 129, 129)
    assert coarse.values.dtype == np.float32


def test_smoothing_keeps_the_value_range_and_removes_the_finest_oscillation():
    rng = np.random.default_rng(3)
    vol = UniformVolume(rng.uniform(10, 20, (33, 33, 33)).astype(np.float32))
    coarse = downsample(vol, 2)
    assert vol.value_range[0] <= coarse.value_range[0] and coarse.value_range[1] <= vol.value_range[1]
    # the Nyquist pattern (+1, -1, +1, ...) along x averages out in the interior
    checker = np.where(np.arange(33) % 2 == 0, 1.0, -1.0).astype(np.float32)
    flat = downsample(UniformVolume(np.broadcast_to(checker, (4, 4, 33)).copy()), 2)
    assert np.abs(flat.values[..., 1:-1]).max() < 1e-6


def test_non_finite_values_stay_transparent_locally():
    values = np.ones((17, 17, 17), np.float32)
    values[8, 8, 8] = np.nan
    values[0, 0, 0] = np.inf
    coarse = downsample(UniformVolume(values), 2)
    bad = ~np.isfinite(coarse.values)
    assert bad[4, 4, 4] and bad[0, 0, 0]
    assert bad.sum() <= 2 * 27  # each non-finite voxel reaches at most its coarse neighbours
    assert np.all(coarse.values[np.isfinite(coarse.values)] == 1.0)


@pytest.mark.parametrize("factor", [0, 3, -2, 16, 2.0, True])
def test_bad_factor_is_a_one_line_error(factor):
    with pytest.raises(VolrenError, match="downsampling factor"):
        downsample(UniformVolume(np.zeros((4, 4, 4), np.float32)), factor)
