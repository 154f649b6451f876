"""The `vtk` renderer against closed forms, and its error paths and resource hygiene."""

from __future__ import annotations

import ctypes

import numpy as np
import pytest

from tests.renderers.analytic import box_path_lengths, homogeneous_image, rmse
from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.default_tf import default_transfer_function
from volren.model.settings import RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import TetVolume, UniformVolume
from volren.renderers import opengl
from volren.renderers.registry import registry
from volren.testing.metrics import image_error
from volren.testing.reference_images import reference_image

pytestmark = [pytest.mark.vtk, pytest.mark.usefixtures("opengl")]

# One 8-bit step plus the sampling error of a homogeneous medium (which is exact up to rounding).
LSB = 1.0 / 255.0


def lattice_tets(n: int, spacing=(1.0, 1.0, 1.0)) -> TetVolume:
    """A box of n^3 cells, each split into 6 tetrahedra (conforming Kuhn split)."""
    from volren.samples import _KUHN_PATHS

    grid = np.stack(np.meshgrid(*[np.arange(n + 1) * s for s in spacing], indexing="ij"), -1)
    index = np.arange((n + 1) ** 3).reshape(n + 1, n + 1, n + 1)
    tets = []
    for i in range(n):
        for j in range(n):
            for k in range(n):
                for path in _KUHN_PATHS:
                    tets.append([index[i + a, j + b, k + c] for a, b, c in path])
    from volren.model.tet_repair import repair_tets

    points = grid.reshape(-1, 3)
    return TetVolume(points, repair_tets(points, np.array(tets)).tets, np.ones(len(points)), name="lattice")


@pytest.fixture
def vtk_renderer():
    renderer = registry.create("vtk")
    yield renderer
    renderer.release()


# Median interior error bound per mapper. The fixed-point mapper keeps a systematic error of a
# few 8-bit steps (15-bit fixed-point tables; ../shared/scenes/README.md measured 0.003-0.011 RMSE
# on the smooth scenes); the GPU mappers are exact up to the framebuffer's rounding.
MEDIAN_BOUND = {"smart": 1.5 * LSB, "gpu": 1.5 * LSB, "fixed_point": 6 * LSB}


@pytest.mark.parametrize("mapper", ["smart", "gpu", "fixed_point"])
@pytest.mark.parametrize("parallel", [True, False])
def test_homogeneous_box_matches_the_closed_form(vtk_renderer, mapper, parallel):
    volume = UniformVolume(np.full((12, 20, 16), 3.0, np.float32), spacing=(1.0, 0.5, 1.5), origin=(2, -1, 0))
    tf = TransferFunction1D.constant(0.1, (0.2, 0.6, 1.0), opacity_unit_distance=2.0)
    camera = Camera.orbit(volume.bounds, 30, 20, 1.0, parallel)
    vtk_renderer.set_volume(volume)
    vtk_renderer.set_transfer_function(tf)
    vtk_renderer.set_settings(RenderSettings(step=0.25, options={"mapper": mapper}))
    image = vtk_renderer.render(camera, 48, 40)
    expected = homogeneous_image(box_path_lengths(camera, 48, 40, volume.bounds), (0.2, 0.6, 1.0), 0.1, 2.0)
    error = np.abs(image - expected)
    # Interior pixels: 8-bit rounding and the mapper's last partial step. Silhouette pixels may
    # differ by more (a ray that grazes the box), so they are bounded through the RMSE.
    inside = box_path_lengths(camera, 48, 40, volume.bounds) > 2.0
    print(
        f"{mapper} parallel={parallel}: rmse {rmse(image, expected):.4f}, interior max {error[inside].max():.4f}"
    )
    assert np.median(error[inside]) <= MEDIAN_BOUND[mapper]
    assert rmse(image, expected) < 0.015


@pytest.mark.parametrize(
    "mapper, preintegration", [("raycast", False), ("raycast", True), ("projected", False)]
)
def test_homogeneous_tet_box_matches_the_closed_form(vtk_renderer, mapper, preintegration):
    volume = lattice_tets(6, spacing=(1.0, 1.2, 0.8))
    tf = TransferFunction1D.constant(0.3, (1.0, 0.5, 0.25), opacity_unit_distance=1.5)
    camera = Camera.orbit(volume.bounds, 30, 20, 1.0)
    vtk_renderer.set_volume(volume)
    vtk_renderer.set_transfer_function(tf)
    vtk_renderer.set_settings(RenderSettings(preintegration=preintegration, options={"mapper": mapper}))
    image = vtk_renderer.render(camera, 40, 40)
    lengths = box_path_lengths(camera, 40, 40, volume.bounds)
    expected = homogeneous_image(lengths, (1.0, 0.5, 0.25), 0.3, 1.5)
    error = np.abs(image - expected)
    print(
        f"{mapper} pre={preintegration}: rmse {rmse(image, expected):.4f}, median {np.median(error[lengths > 1]):.4f}"
    )
    # The extinction conversion (a -> -ln(1 - a)) makes VTK's unstructured mappers draw our
    # model: without it the alpha would be 1 - exp(-0.3 L / 1.5), far below the expected value.
    assert np.median(error[lengths > 1]) < 0.01
    assert rmse(image, expected) < 0.02


def test_nan_voxels_are_transparent(vtk_renderer):
    values = np.full((16, 16, 16), 5.0, np.float32)
    values[:, :, 8:] = np.nan
    volume = UniformVolume(values)
    tf = TransferFunction1D.ramp(0, 10, 0.5)
    vtk_renderer.set_volume(volume)
    vtk_renderer.set_transfer_function(tf)
    camera = Camera.orbit(volume.bounds, 0, 0, 1.0, parallel=True)
    image = vtk_renderer.render(camera, 32, 32)
    assert np.all(np.isfinite(image))
    # The box spans columns 7..24; x <= 7 (columns 7..15) is finite and visible, the NaN half
    # (x >= 8, columns 17..24) adds nothing.
    assert np.all(image[16, 8:14, 3] > 0.5) and np.all(image[16, 17:, 3] == 0.0)


@pytest.mark.parametrize("mapper", ["gpu", "fixed_point"])
@pytest.mark.parametrize("with_nan", [False, True])
def test_float32_data_out_to_the_type_limits_matches_the_reference(vtk_renderer, tmp_path, mapper, with_nan):
    """VTK's float32 arithmetic over such a span drew blank frames; the default TF spans it all."""
    big = np.finfo(np.float32).max
    values = np.random.default_rng(0).random((16, 16, 16), dtype=np.float32)
    values[:, :, :5] = big
    values[0, 0, 0] = -big
    if with_nan:  # the sentinel goes a data range further down
        values[8, 8, 8] = np.nan
    volume = UniformVolume(values)
    tf = default_transfer_function(volume)
    camera = Camera.orbit(volume.bounds, 30, 20, 1.0)
    vtk_renderer.set_volume(volume)
    vtk_renderer.set_transfer_function(tf)
    vtk_renderer.set_settings(RenderSettings(options={"mapper": mapper}))
    reference = reference_image(volume, tf, camera, 32, 32, folder=tmp_path)
    error = image_error(vtk_renderer.render(camera, 32, 32), reference)
    assert reference[..., 3].mean() > 0.15  # a blank frame is far off
    assert error.rmse <= vtk_renderer.capabilities.kinds["uniform"].accuracy.rmse, error


def test_render_is_repeatable_and_follows_tf_edits(vtk_renderer):
    volume = UniformVolume(np.linspace(0, 1, 16**3, dtype=np.float32).reshape(16, 16, 16))
    tf = TransferFunction1D.ramp(0, 1, 0.8)
    vtk_renderer.set_volume(volume)
    vtk_renderer.set_transfer_function(tf)
    camera = Camera.orbit(volume.bounds, 30, 20, 1.0)
    first = vtk_renderer.render(camera, 32, 32)
    assert np.array_equal(first, vtk_renderer.render(camera, 32, 32))
    tf.set_opacity_points([[0, 0], [1, 0.1]])
    assert vtk_renderer.render(camera, 32, 32)[..., 3].sum() < 0.5 * first[..., 3].sum()


def test_unsupported_requests_are_clear_errors(vtk_renderer):
    vtk_renderer.set_volume(lattice_tets(2))
    vtk_renderer.set_transfer_function(TransferFunction1D.ramp(0, 1))
    camera = Camera.orbit((0, 2, 0, 2, 0, 2))
    for settings, message in [
        (RenderSettings(blend_mode="maximum"), "no maximum blend mode for tet"),
        (RenderSettings(shade=True), "no shading for tet"),
        (RenderSettings(options={"mapper": "gpu"}), "cannot draw tet volumes"),
        (RenderSettings(preintegration=True, options={"mapper": "projected"}), "no pre-integration"),
    ]:
        vtk_renderer.set_settings(settings)
        with pytest.raises(VolrenError, match=message):
            vtk_renderer.render(camera, 8, 8)
    with pytest.raises(VolrenError, match="has no option"):
        vtk_renderer.set_settings(RenderSettings(options={"colour": 1}))
    with pytest.raises(VolrenError, match="renderer vtk: option mapper must be one of 'auto', 'smart'"):
        vtk_renderer.set_settings(RenderSettings(options={"mapper": "nope"}))
    with pytest.raises(VolrenError, match="image size"):
        vtk_renderer.render(camera, 0, 8)


def test_release_frees_the_window_and_blocks_further_use():
    renderer = registry.create("vtk")
    renderer.set_volume(UniformVolume(np.zeros((4, 4, 4), np.uint8)))
    renderer.set_transfer_function(TransferFunction1D.ramp(0, 1))
    renderer.render(Camera.orbit((0, 3, 0, 3, 0, 3)), 8, 8)
    renderer.release()
    assert renderer._window is None and renderer._mapper is None
    with pytest.raises(VolrenError, match="released"):
        renderer.render(Camera.orbit((0, 3, 0, 3, 0, 3)), 8, 8)


def test_missing_opengl_libraries_name_the_debian_packages(monkeypatch):
    real_cdll = ctypes.CDLL

    def no_egl(name, *args, **kwargs):
        if "EGL" in name:
            raise OSError(f"{name}: cannot open shared object file")
        return real_cdll(name, *args, **kwargs)

    monkeypatch.setattr(ctypes, "CDLL", no_egl)
    opengl.opengl_problem.cache_clear()
    try:
        with pytest.raises(VolrenError, match="libegl1 libgl1 libgl1-mesa-dri"):
            opengl.require_opengl()
    finally:
        opengl.opengl_problem.cache_clear()


def test_step_changes_apply_in_place(vtk_renderer):
    x = np.linspace(0, 1, 24, dtype=np.float32)
    volume = UniformVolume(np.broadcast_to(x[None, None, :] * x[None, :, None], (24, 24, 24)).copy())
    tf = TransferFunction1D([[0, 1, 1, 1]], [[0.3, 0.0], [0.31, 1.0], [0.33, 1.0], [0.34, 0.0]])
    camera = Camera.orbit(volume.bounds, 30, 20, 1.0)
    vtk_renderer.set_volume(volume)
    vtk_renderer.set_transfer_function(tf)
    images = {}
    for step in (1.0, 0.125):
        vtk_renderer.set_settings(RenderSettings(step=step))
        images[step] = vtk_renderer.render(camera, 32, 32)
        assert vtk_renderer.last_frame.counters["sample_distance"] == pytest.approx(step)
        with registry.create("vtk") as fresh:
            fresh.set_volume(volume)
            fresh.set_transfer_function(tf)
            fresh.set_settings(RenderSettings(step=step))
            assert np.array_equal(fresh.render(camera, 32, 32), images[step])
    assert not np.array_equal(images[1.0], images[0.125])  # the thin shell needs the fine step


def test_step_changes_keep_the_mesh_mapper(vtk_renderer):
    vtk_renderer.set_volume(lattice_tets(2))
    vtk_renderer.set_transfer_function(TransferFunction1D.constant(0.3))
    camera = Camera.orbit((0, 2, 0, 2, 0, 2), 30, 20)
    vtk_renderer.render(camera, 16, 16)
    mapper = vtk_renderer._mapper
    vtk_renderer.set_settings(RenderSettings(step=2.0))
    vtk_renderer.render(camera, 16, 16)
    assert vtk_renderer._mapper is mapper
    vtk_renderer.set_settings(RenderSettings(step=2.0, preintegration=True))
    vtk_renderer.render(camera, 16, 16)
    assert vtk_renderer._mapper is not mapper  # a new ray integrator is a new mapper
