"""raycast's C march draws numba's image with 2D transfer functions (`march2d`): the hard cases of
the 1D comparison (thin sheets and tubes, a one-voxel object, noise, NaN and infinities, anisotropy,
tiny grids, a camera inside the grid, clip planes, every brick size) under TFs whose samples read
the gradient (a Gaussian widget) or not (a 1D band), each drawn by both kernels and compared to
float rounding."""

from __future__ import annotations

import numpy as np
import pytest

from volren.model import Camera, TFWidget, TransferFunction2D, UniformVolume
from volren.model.clip_region import ClipRegion
from volren.renderers.raycast import march_native
from volren.renderers.raycast.march_inputs import gradients

from .test_raycast_native import (
    ATOL,
    STEP_TF,
    _both,
    _compare,
    anisotropic_scene,
    clipped_scene,
    inside_scene,
    special_values_scene,
    thin_structures_scene,
    tiny_grid_scene,
)


def _largest_gradient(volume: UniformVolume) -> float:
    g = gradients(np.asarray(volume.values), volume.spacing)
    return float(np.sqrt((g.values.astype(np.float64) ** 2).sum(-1)).max() * g.unit) or 1.0


def _tf(volume: UniformVolume, band: bool = True, opacity: float = 0.6) -> TransferFunction2D:
    """A Gaussian widget over the upper values and middle gradients (its samples read the gradient),
    over a 1D band that covers every gradient (its samples do not)."""
    finite = np.asarray(volume.values, np.float64)
    finite = finite[np.isfinite(finite)]
    lo, hi = float(finite.min()), float(finite.max())
    gmax = _largest_gradient(volume)
    widgets = [TFWidget.gaussian((lo + 0.7 * (hi - lo), 0.4 * gmax), (0.1 * (hi - lo), 0.25 * gmax),
                                 (1.0, 0.5, 0.2), opacity)]  # fmt: skip
    if band:
        scaled = STEP_TF.copy()
        scaled.set_color_points(np.column_stack([lo + (hi - lo) * STEP_TF.color_points[:, 0] / 255,
                                                 STEP_TF.color_points[:, 1:]]))  # fmt: skip
        scaled.set_opacity_points(np.column_stack([lo + (hi - lo) * STEP_TF.opacity_points[:, 0] / 255,
                                                   0.3 * STEP_TF.opacity_points[:, 1:]]))  # fmt: skip
        widgets.append(TFWidget.from_1d(scaled, (0.0, gmax)))
    return TransferFunction2D((lo, hi), (0.0, gmax), widgets, 2.0)


@pytest.fixture(autouse=True)
def needs_the_c_build():
    if march_native._library() is None:
        pytest.skip("no C compiler here: the numba kernels draw")


@pytest.mark.parametrize("band", [False, True])
@pytest.mark.parametrize("parallel", [False, True])
@pytest.mark.parametrize("brick", [1, 3, 4, 8])
def test_thin_and_tiny_structures_draw_alike(band, parallel, brick, monkeypatch):
    volume, camera = thin_structures_scene(parallel)
    _compare(volume, _tf(volume, band), camera, monkeypatch, step=0.6, options={"brick_size": brick})


@pytest.mark.parametrize("termination", [0.9, 1.0])
def test_nan_and_infinite_values_draw_alike(termination, monkeypatch):
    volume, camera = special_values_scene()
    _compare(volume, _tf(volume), camera, monkeypatch, step=0.4, options={"termination_alpha": termination})


@pytest.mark.parametrize("skipping", [True, False])
@pytest.mark.parametrize("offsets", ["interleaved", "midpoint"])
def test_smooth_anisotropic_fields_draw_alike(skipping, offsets, monkeypatch):
    volume, camera = anisotropic_scene()
    _compare(volume, _tf(volume), camera, monkeypatch, step=0.35,
             options={"empty_space_skipping": skipping, "depth_offsets": offsets})  # fmt: skip


def test_clipped_frames_draw_alike(monkeypatch):
    volume, camera, planes = clipped_scene()
    _compare(volume, _tf(volume), camera, monkeypatch, step=0.5, clip=ClipRegion(planes))


@pytest.mark.parametrize("shape", [(2, 2, 2), (2, 9, 8), (7, 2, 6), (5, 6, 2)])
def test_tiny_and_flat_grids_draw_alike(shape, monkeypatch):
    volume, cameras = tiny_grid_scene(shape)
    for camera in cameras:
        numba_image, c_image, _, _ = _both(volume, _tf(volume), camera, monkeypatch, step=0.3)
        np.testing.assert_allclose(c_image, numba_image, atol=ATOL, rtol=0)


def test_a_camera_inside_the_grid_draws_alike(monkeypatch):
    volume, camera = inside_scene()
    _compare(volume, _tf(volume), camera, monkeypatch, step=0.5)


def test_an_opaque_ray_stops_where_numba_stops(monkeypatch):
    """Early termination inside an eight-sample run: the same samples counted as numba's."""
    z, y, x = np.mgrid[0:24, 0:24, 0:24]
    volume = UniformVolume((100 + 4 * x + 2 * y + z).astype(np.uint8))
    camera = Camera.orbit(volume.bounds, 0, 0, parallel=True)
    numba_image, c_image, numba_samples, c_samples = _both(
        volume, _tf(volume, band=False, opacity=1.0), camera, monkeypatch, step=0.5
    )
    assert numba_image[..., 3].max() > 0.9
    np.testing.assert_allclose(c_image, numba_image, atol=ATOL, rtol=0)
    assert c_samples == numba_samples


def test_a_grid_too_large_for_the_gradients_offsets_is_left_to_numba(monkeypatch):
    values = march_native.padded(np.zeros((4, 5, 6), np.uint8))
    assert march_native.kernels(values, "2d") is not None
    monkeypatch.setattr(march_native, "MAX_VALUES_2D", values.size - 1)
    assert march_native.kernels(values, "2d") is None
    assert march_native.kernels(values) is not None


def test_a_2d_frame_the_c_march_draws_does_not_import_numba():
    """The 2D inputs are numpy's (`march_inputs`): a frame of a 2D TF drawn by the C march pays no
    numba import; with ``VOLREN_NATIVE=0`` numba's march draws it."""
    import os
    import subprocess
    import sys

    code = (
        "import sys\n"
        "import numpy as np\n"
        "import volren\n"
        "from volren.model import TFWidget, TransferFunction2D, UniformVolume\n"
        "z, y, x = np.mgrid[0:12, 0:11, 0:13].astype(np.float32)\n"
        "vol = UniformVolume(np.exp(-((x - 6) ** 2 + (y - 5) ** 2 + (z - 6) ** 2) / 18).astype(np.float32))\n"
        "w = TFWidget.gaussian((0.5, 0.1), (0.2, 0.1), (1, 0.5, 0.2), 0.6)\n"
        "image = volren.render(vol, TransferFunction2D((0.0, 1.0), (0.0, 0.3), [w]), renderer='raycast', size=(16, 16))\n"
        "print(bool(image[..., 3].max() > 0), 'numba' in sys.modules)\n"
    )
    for native, numba_loaded in (("1", False), ("0", True)):
        result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300,
                                env={**os.environ, "VOLREN_NATIVE": native})  # fmt: skip
        assert result.returncode == 0, result.stderr
        assert result.stdout.split() == ["True", str(numba_loaded)]
