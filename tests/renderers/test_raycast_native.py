"""raycast's C march draws numba's image: hard cases (thin sheets and tubes, a one-voxel object,
noise, steps, NaN and infinities, anisotropy, tiny grids, a camera inside the grid, clip planes and
cut faces, pre-integration, every brick size), each drawn by both kernels and compared to float
rounding; and the C build's own rules (fallback, slack, one-line failures)."""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest

from volren.kernels import native
from volren.model import Camera, TransferFunction1D, UniformVolume
from volren.model.clip_region import ClipPlane, ClipRegion
from volren.renderers.raycast import RaycastRenderer, march_native
from volren.testing.render_helpers import SHELL_TF, SMOOTH_TF, field, render_checked

from .raycast_backends import use_backend

draw = partial(render_checked, RaycastRenderer)

#: C interpolates a sample's eight values in single precision (numba in double): images agree to
#: a few float32 roundings of the colour.
ATOL = 2e-5

STEP_TF = TransferFunction1D([[0, 1, 0.2, 0.1], [255, 0.1, 0.4, 1.0]],
                             [[0, 0.0], [99, 0.0], [100, 0.9], [255, 0.9]], 2.0)  # fmt: skip


def _sheets_and_tubes() -> UniformVolume:
    """A one-voxel sheet, a thin tube, a single bright voxel and noise, 8-bit."""
    rng = np.random.default_rng(3)
    values = rng.integers(0, 40, size=(33, 30, 31)).astype(np.uint8)
    values[:, 14, :] = 200  # a sheet one voxel thick
    z, y, x = np.mgrid[0:33, 0:30, 0:31]
    values[(x - 9) ** 2 + (z - 20) ** 2 <= 1] = 255  # a tube along y
    values[5, 5, 5] = 250  # a tiny object
    return UniformVolume(values, spacing=(1.0, 0.7, 1.6))


def _specials() -> UniformVolume:
    """A float field with NaN, +inf and -inf holes."""
    volume = field((17, 15, 19))
    values = volume.values.copy()
    values[8, 7, 3:9] = np.nan
    values[2, 3, 4] = np.inf
    values[12, 2, 10] = -np.inf
    return UniformVolume(values)


def _both(volume, tf, camera, monkeypatch, size=(36, 30), **settings):
    """(numba's image, C's image, numba's samples, C's samples) of the same frame."""
    images, samples = [], []
    for backend in ("numba", "c"):
        with monkeypatch.context() as patch:
            use_backend(backend, patch)
            image, renderer = draw(volume, tf, camera, size, **settings)
        images.append(image)
        samples.append(renderer.last_frame.counters["samples"])
    return images[0], images[1], samples[0], samples[1]


def _compare(volume, tf, camera, monkeypatch, size=(36, 30), **settings):
    numba_image, c_image, numba_samples, c_samples = _both(volume, tf, camera, monkeypatch, size, **settings)
    assert numba_image[..., 3].max() > 0.05, "the scene must show something"
    np.testing.assert_allclose(c_image, numba_image, atol=ATOL, rtol=0)
    assert abs(c_samples - numba_samples) <= 0.002 * numba_samples + 2


# The hard cases both marches draw, with the camera each is seen from (the 2D comparison's too).
def thin_structures_scene(parallel: bool) -> tuple[UniformVolume, Camera]:
    volume = _sheets_and_tubes()
    return volume, Camera.orbit(volume.bounds, 37, 21, zoom=1.3, parallel=parallel)


def special_values_scene() -> tuple[UniformVolume, Camera]:
    volume = _specials()
    return volume, Camera.orbit(volume.bounds, -50, 35, zoom=1.1)


def anisotropic_scene() -> tuple[UniformVolume, Camera]:
    volume = field((20, 22, 24), spacing=(0.5, 1.0, 2.5))
    return volume, Camera.orbit(volume.bounds, 120, -40, zoom=1.4)


def clipped_scene() -> tuple[UniformVolume, Camera, tuple[ClipPlane, ClipPlane]]:
    """A smooth field, two clip planes through it and a camera that sees both cuts."""
    volume = field((20, 22, 24))
    lo, hi = np.array(volume.bounds[::2]), np.array(volume.bounds[1::2])
    middle = (lo + hi) / 2
    planes = (ClipPlane(tuple(middle), (0.6, 0.0, 0.8)), ClipPlane(tuple(middle + 1.5), (0.0, -1.0, 0.2)))
    return volume, Camera.orbit(volume.bounds, 30, 25, zoom=1.2), planes


def tiny_grid_scene(shape: tuple[int, int, int]) -> tuple[UniformVolume, list[Camera]]:
    """A grid of steps of `shape` and three cameras: along x, along y and from above at an angle."""
    volume = UniformVolume((np.arange(np.prod(shape)).reshape(shape) % 5 * 50).astype(np.uint8))
    return volume, [Camera.orbit(volume.bounds, a, e, zoom=1.2) for a, e in ((0, 0), (90, 0), (30, 60))]


def inside_scene() -> tuple[UniformVolume, Camera]:
    volume = field((30, 30, 30))
    return volume, Camera.orbit(volume.bounds, 20, 10, zoom=6.0)


@pytest.mark.parametrize("pre", [False, True])
@pytest.mark.parametrize("parallel", [False, True])
@pytest.mark.parametrize("brick", [1, 3, 4, 8])
def test_thin_and_tiny_structures_draw_alike(pre, parallel, brick, monkeypatch):
    volume, camera = thin_structures_scene(parallel)
    _compare(
        volume, STEP_TF, camera, monkeypatch, step=0.6, preintegration=pre, options={"brick_size": brick}
    )


@pytest.mark.parametrize("pre", [False, True])
@pytest.mark.parametrize("termination", [0.9, 1.0])
def test_nan_and_infinite_values_draw_alike(pre, termination, monkeypatch):
    volume, camera = special_values_scene()
    _compare(volume, SHELL_TF, camera, monkeypatch, step=0.4, preintegration=pre,
             options={"termination_alpha": termination})  # fmt: skip


@pytest.mark.parametrize("skipping", [True, False])
@pytest.mark.parametrize("offsets", ["interleaved", "midpoint"])
def test_smooth_fields_draw_alike(skipping, offsets, monkeypatch):
    volume, camera = anisotropic_scene()
    _compare(volume, SMOOTH_TF, camera, monkeypatch, step=0.35,
             options={"empty_space_skipping": skipping, "depth_offsets": offsets})  # fmt: skip


@pytest.mark.parametrize("pre", [False, True])
@pytest.mark.parametrize("cap", [False, True])
def test_clipped_and_capped_frames_draw_alike(pre, cap, monkeypatch):
    volume, camera, planes = clipped_scene()
    _compare(volume, SHELL_TF, camera, monkeypatch, step=0.5, preintegration=pre,
             clip=ClipRegion(planes, None, cap))  # fmt: skip


@pytest.mark.parametrize("shape", [(2, 2, 2), (2, 9, 8), (7, 2, 6), (5, 6, 2)])
def test_tiny_and_flat_grids_draw_alike(shape, monkeypatch):
    """A grid of one cell, and grids one cell thick (the cell index is 0 on that axis)."""
    volume, cameras = tiny_grid_scene(shape)
    for camera in cameras:
        numba_image, c_image, _, _ = _both(volume, STEP_TF, camera, monkeypatch, step=0.3)
        np.testing.assert_allclose(c_image, numba_image, atol=ATOL, rtol=0)


def test_a_camera_inside_the_grid_draws_alike(monkeypatch):
    volume, camera = inside_scene()
    _compare(volume, SMOOTH_TF, camera, monkeypatch, step=0.5)


def test_an_opaque_ray_stops_where_numba_stops(monkeypatch):
    """Early termination inside an eight-sample run: the C march counts the samples up to the one
    that made the ray opaque, as numba does."""
    values = np.full((24, 24, 24), 200, np.uint8)
    volume = UniformVolume(values)
    camera = Camera.orbit(volume.bounds, 0, 0, parallel=True)
    numba_image, c_image, numba_samples, c_samples = _both(volume, STEP_TF, camera, monkeypatch, step=0.5)
    np.testing.assert_allclose(c_image, numba_image, atol=ATOL, rtol=0)
    assert c_samples == numba_samples


def test_an_8_bit_grid_without_slack_is_left_to_numba():
    """The vector path reads four bytes at a value's offset: an 8-bit grid must own slack bytes
    after its last value (`padded`), else the C march is not used for it."""
    bare = np.zeros((4, 5, 6), np.uint8)
    assert march_native.kernels(bare) is None
    assert march_native.kernels(bare[1:]) is None  # a view whose owner ends where it ends
    padded = march_native.padded(bare)
    assert padded.shape == bare.shape and padded.dtype == np.uint8
    if march_native._library() is not None:
        assert march_native.kernels(padded) is not None
        assert march_native.kernels(np.zeros((4, 5, 6), np.float32)) is not None
    assert march_native.kernels(np.zeros((4, 5, 6), np.int16)) is None


def test_no_compiler_or_a_failed_build_leaves_numba_in_charge(monkeypatch, tmp_path):
    source = tmp_path / "broken.c"
    source.write_text("this is not C\n")
    monkeypatch.setenv("VOLREN_NATIVE_CACHE", str(tmp_path / "cache"))
    native._load.cache_clear()
    try:
        assert native.load(source) is None  # the build fails: no library, no exception
        assert not list((tmp_path / "cache").glob("*"))  # and no half-written file is left
        monkeypatch.setattr(native, "compiler", lambda: None)
        assert native.load(march_native.SOURCE) is None
        monkeypatch.setenv("VOLREN_NATIVE", "0")
        assert not native.enabled()
    finally:
        native._load.cache_clear()


def test_a_built_library_is_reused_from_the_cache(monkeypatch, tmp_path):
    if native.compiler() is None:
        pytest.skip("no C compiler here")
    monkeypatch.setenv("VOLREN_NATIVE_CACHE", str(tmp_path))
    native._load.cache_clear()
    try:
        assert native.load(march_native.SOURCE) is not None
        built = list(tmp_path.glob("march-*.so"))
        assert len(built) == 1
        stamp = built[0].stat().st_mtime_ns
        native._load.cache_clear()
        assert native.load(march_native.SOURCE) is not None
        assert built[0].stat().st_mtime_ns == stamp
    finally:
        native._load.cache_clear()


def _render_in_a_new_process(tmp_path, env_extra):
    """(return code, stderr, whether numba was imported) of `volren render` on the bundled
    marschner_lobb sample with raycast, in a new interpreter."""
    import os
    import subprocess
    import sys

    from volren.samples import sample_paths

    volume, tf = sample_paths("marschner_lobb")
    code = (
        "import sys\n"
        "from volren.cli.main import main\n"
        "code = main(sys.argv[1:])\n"
        "print('numba' in sys.modules)\n"
        "sys.exit(code)\n"
    )
    args = ["render", str(volume), "--tf", str(tf), "-o", str(tmp_path / "out.png"), "--size", "24",
            "--renderer", "raycast"]  # fmt: skip
    result = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=300,
                            env={**os.environ, **env_extra})  # fmt: skip
    return result.returncode, result.stderr, result.stdout.splitlines()[-1] == "True"


def test_a_frame_the_c_march_draws_does_not_import_numba(tmp_path):
    """numba's import and first call cost a one-shot render about a second (`benchmarks.oneshot`):
    with the C march, a 1D frame at the default level needs none of it; without, numba draws."""
    if march_native._library() is None:
        pytest.skip("no C compiler here: the numba kernels draw")
    code, err, numba_loaded = _render_in_a_new_process(tmp_path, {})
    assert code == 0, err
    assert not numba_loaded
    code, err, numba_loaded = _render_in_a_new_process(tmp_path, {"VOLREN_NATIVE": "0"})
    assert code == 0, err
    assert numba_loaded


def test_the_vector_path_is_gathers_in_the_built_library():
    """Vectorized by construction, checked in the machine code: the library built with AVX2 holds
    the gathers of the eight-segment path (float and 32-bit integer)."""
    import shutil
    import subprocess

    if not march_native.vector_path() or shutil.which("objdump") is None:
        pytest.skip("no AVX2 build here, or no objdump to read it")
    path = march_native._library()._name  # type: ignore[union-attr]
    code = subprocess.run(["objdump", "-d", path], capture_output=True, text=True, check=True).stdout
    assert "vgatherdps" in code and "vpgatherdd" in code


def test_a_new_build_removes_the_libraries_of_older_sources(monkeypatch, tmp_path):
    if native.compiler() is None:
        pytest.skip("no C compiler here")
    monkeypatch.setenv("VOLREN_NATIVE_CACHE", str(tmp_path))
    source = tmp_path / "probe.c"
    native._load.cache_clear()
    try:
        source.write_text("int answer(void) { return 41; }\n")
        assert native.load(source).answer() == 41
        source.write_text("int answer(void) { return 42; }\n")
        native._load.cache_clear()
        assert native.load(source).answer() == 42
        assert len(list(tmp_path.glob("probe-*.so"))) == 1
    finally:
        native._load.cache_clear()


def test_outputs_too_small_for_what_the_c_march_writes_are_refused(monkeypatch):
    """C checks no bound: an output array smaller than the image, counts without a row for every
    tile or pixel, or a pixel outside the image is a ValueError before any write."""
    if march_native._library() is None:
        pytest.skip("no C compiler here: the numba kernels draw")
    volume = field((6, 7, 8))
    inputs = []
    real = march_native.march

    def spy(*args):
        inputs.append(args[:5])
        return real(*args)

    monkeypatch.setattr(march_native, "march", spy)
    draw(volume, SHELL_TF, Camera.orbit(volume.bounds, 30, 20), (16, 16), step=0.5)
    args = inputs[0]
    tiles = np.arange(4, dtype=np.int64)
    with pytest.raises(ValueError, match="RGBA"):
        real(*args, tiles, np.zeros((255, 4), np.float32), np.zeros((4, 4), np.int64))
    with pytest.raises(ValueError, match="counts"):
        real(*args, tiles, np.zeros((256, 4), np.float32), np.zeros((3, 4), np.int64))
    with pytest.raises(ValueError, match="in the image"):
        march_native.march_pixels(*args, np.array([256], np.int64), np.zeros((1, 4), np.float32),
                                  np.zeros((1, 4), np.int64))  # fmt: skip
    real(*args, tiles, np.zeros((256, 4), np.float32), np.zeros((4, 4), np.int64))  # the right sizes draw
