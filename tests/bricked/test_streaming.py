"""Out of core on one machine (issue 24): an OME-Zarr level streamed brick by brick through a
bounded chunk cache equals the level rendered whole; transparent bricks are never read; the level
of detail follows the projected voxel size; bad chunks are one-line errors naming them."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from volren.api import prepared_renderer
from volren.bricked.sort_last import render_bricked
from volren.bricked.zarr_input import ZarrInput
from volren.bricked.zarr_source import ZarrSource, level_for_view
from volren.errors import VolrenError
from volren.io import ome_zarr_io
from volren.model.camera import Camera
from volren.model.settings import RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import UniformVolume
from volren.renderers.registry import registry

zarr = pytest.importorskip("zarr", reason="volren[zarr] is part of the test set-up")

TF = TransferFunction1D(
    [[0, 0.1, 0.4, 1.0], [2000, 0.9, 0.9, 0.2], [4000, 1.0, 0.2, 0.1]],
    [[0, 0.0], [1000, 0.05], [2500, 0.4], [4000, 0.2]],
    3.0,
)


@pytest.fixture
def image_path(tmp_path):
    z, y, x = np.meshgrid(np.arange(19), np.arange(26), np.arange(31), indexing="ij")
    values = (2000 + 1500 * np.sin(0.3 * x) * np.cos(0.25 * y) + 40 * z).astype(np.uint16)
    volume = UniformVolume(values, spacing=(0.8, 1.0, 1.3), origin=(1.0, -2.0, 3.0), name="field")
    path = tmp_path / "field.zarr"
    ome_zarr_io.save_ome_zarr(volume, path, chunk=8, levels=2)
    return path


def render_both(path, name, settings, budget, camera=None):
    image = ome_zarr_io.open_multiscale(path)
    whole = ome_zarr_io.load_level(path, 0)
    camera = camera or Camera.orbit(whole.bounds, 35, 25, zoom=1.1)
    with prepared_renderer(name, whole, TF, settings) as renderer:
        expected = renderer.render(camera, 24, 20)
        source = ZarrSource(image, 0, budget)
        streamed, frame = render_bricked(renderer, source, TF, camera, 24, 20, brick=source.brick)
    return expected, streamed, frame, source


def rmse(a, b):
    return float(np.sqrt(np.mean((a.astype(np.float64) - b) ** 2)))


def test_a_streamed_level_equals_the_level_read_whole_within_the_cache_budget(image_path):
    budget = 6 * 8**3 * 2  # six uint16 chunks of the 4 x 4 x 3 = 48
    expected, streamed, frame, source = render_both(image_path, "reference", RenderSettings(), budget)
    assert expected[..., 3].max() > 0.2
    assert rmse(streamed, expected) <= 1e-5
    stats = source.cache.stats
    assert stats.peak_bytes <= budget and stats.evictions > 0 and stats.hits > 0
    assert frame.drawn == frame.bricks  # this TF shows every brick


@pytest.mark.usefixtures("opengl")
def test_the_slicer_streams_with_pre_integration_and_shading(image_path):
    settings = RenderSettings(preintegration=True, shade=True, options={"early_termination": False})
    expected, streamed, frame, _ = render_both(image_path, "slicer", settings, 1 << 20)
    assert frame.ghost == 2 and rmse(streamed, expected) <= 1e-5


def test_bricks_the_tf_hides_are_never_read(tmp_path, monkeypatch):
    values = np.full((40, 40, 40), 1000, dtype=np.uint16)
    values[30:, 30:, 30:] = 3800  # only the far corner shows
    path = tmp_path / "corner.zarr"
    ome_zarr_io.save_ome_zarr(UniformVolume(values, name="corner"), path, chunk=8, levels=1)
    reads: list[tuple] = []
    original = ome_zarr_io.read_brick

    def counting(image, level, array, index):
        reads.append(index)
        return original(image, level, array, index)

    monkeypatch.setattr(ome_zarr_io, "read_brick", counting)
    high_only = TransferFunction1D([[0, 1, 1, 1], [4000, 1, 0, 0]], [[0, 0.0], [3300, 0.0], [4000, 0.8]])
    image = ome_zarr_io.open_multiscale(path)
    source = ZarrSource(image, 0, 1 << 20)
    shown = np.array(
        [i for i, r in zip(np.ndindex(5, 5, 5), image.brick_ranges[0], strict=True) if r[1] > 3300]
    )
    renderer = registry.create("reference")
    try:
        camera = Camera.orbit((0, 39, 0, 39, 0, 39), 10, 10)
        picture, frame = render_bricked(renderer, source, high_only, camera, 16, 16, brick=source.brick)
    finally:
        renderer.release()
    assert picture[..., 3].max() > 0.05 and frame.transparent > 0
    # only chunks that show something, or lie within a brick or its ghost voxels of one, were read
    distance = [int(np.abs(shown - np.array(r)).max(axis=1).min()) for r in set(reads)]
    assert frame.drawn == 27  # the bricks whose voxels or ghost voxels touch the corner's chunks
    assert reads and max(distance) <= 2 and len(set(reads)) == 64


def test_an_image_without_stored_ranges_is_scanned_once(image_path):
    attrs_path = image_path / ".zattrs"
    attrs = json.loads(attrs_path.read_text())
    del attrs["volren"]
    attrs_path.write_text(json.dumps(attrs))
    expected, streamed, _, source = render_both(image_path, "reference", RenderSettings(), 1 << 20)
    assert source.value_range == tuple(float(v) for v in ome_zarr_io.load_level(image_path, 0).value_range)
    assert rmse(streamed, expected) <= 1e-5


def test_a_corrupt_chunk_met_while_streaming_is_one_line_naming_it(image_path):
    chunk = image_path / "0" / "1.2.1"
    chunk.write_bytes(b"not a chunk")
    image = ome_zarr_io.open_multiscale(image_path)
    source = ZarrSource(image, 0, 1 << 20)
    renderer = registry.create("reference")
    try:
        with pytest.raises(VolrenError, match=r"field.zarr: level '0', brick 1\.2\.1: cannot be read") as exc:
            render_bricked(renderer, source, TF, Camera.orbit(ome_zarr_io.load_level(image_path, 1).bounds), 8, 8,
                           brick=source.brick)  # fmt: skip
    finally:
        renderer.release()
    assert "\n" not in str(exc.value)


def test_the_level_of_detail_follows_the_projected_voxel_size(image_path):
    levels = ome_zarr_io.open_multiscale(image_path).levels
    bounds = ome_zarr_io.load_level(image_path, 0).bounds
    camera = Camera.orbit(bounds)
    assert level_for_view(levels, camera, 400, 400) == 0  # voxels of several pixels: the finest
    assert level_for_view(levels, camera, 12, 12) == 1  # a thumbnail: the coarse level
    position = np.asarray(camera.focal_point) + 30 * (np.asarray(camera.position) - camera.focal_point)
    far = replace(camera, position=tuple(position), clipping_range=(1.0, 1e4))  # thirty times as far away
    assert level_for_view(levels, camera, 100, 100) == 0 and level_for_view(levels, far, 100, 100) == 1
    inside = Camera(position=tuple((np.asarray(bounds[0::2]) + bounds[1::2]) / 2), focal_point=(0, 0, 0))
    assert level_for_view(levels, inside, 12, 12) == 0
    parallel = Camera.orbit(bounds, parallel=True)
    assert level_for_view(levels, parallel, 400, 400) == 0 and level_for_view(levels, parallel, 12, 12) == 1


@pytest.mark.filterwarnings("default::volren.errors.VolrenWarning")
def test_volren_render_streams_a_level_larger_than_the_memory_allowed(image_path, tmp_path, capsys):
    from volren.cli.main import main

    flags = ["--renderer", "reference", "--size", "20x16", "--level", "0"]
    assert (
        main(["render", str(image_path), *flags, "--memory", "4KB", "--save-array", str(tmp_path / "s.npy")])
        == 0
    )
    line = capsys.readouterr().out
    assert "(field.zarr level 0 streamed:" in line and "bricks drawn)" in line
    assert main(["render", str(image_path), *flags, "--save-array", str(tmp_path / "w.npy")]) == 0
    assert "(field.zarr level 0 in memory)" in capsys.readouterr().out
    assert rmse(np.load(tmp_path / "s.npy"), np.load(tmp_path / "w.npy")) <= 1e-5
    # a renderer that does not stream bricks gets the finest level that fits, as before
    assert main(["render", str(image_path), "--renderer", "shearwarp", "--size", "16", "--memory", "20KB",
                 "-o", str(tmp_path / "x.png")]) == 0  # fmt: skip
    captured = capsys.readouterr()
    assert "level 1 in memory" in captured.out and "does not stream bricks" in captured.err


def test_zarr_input_refuses_a_level_it_does_not_have(image_path):
    with pytest.raises(VolrenError, match="no level 4; the image has levels 0 to 1"):
        ZarrInput(image_path).check_level(4)


def test_volren_render_from_python_streams_too(image_path):
    import volren

    flags = {"renderer": "reference", "size": (20, 16), "level": 0, "azimuth": 20}
    streamed = volren.render(str(image_path), memory="4KB", **flags)
    whole = volren.render(str(image_path), **flags)
    assert whole[..., 3].max() > 0.1 and rmse(streamed, whole) <= 1e-5
    with pytest.raises(VolrenError, match="memory and level apply to an OME-Zarr image"):
        volren.render(ome_zarr_io.load_level(image_path, 0), memory="1GB")
    with pytest.raises(VolrenError, match="no level 3"):
        volren.render(str(image_path), level=3)
