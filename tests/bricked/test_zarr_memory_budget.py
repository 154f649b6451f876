"""--memory holds for what reading an OME-Zarr level whole costs: its values and the renderer's own
copies of them (`zarr_input.RENDERER_COPY_BYTES`); a level whose values fit but whose copies do not
is streamed, or, for a renderer that cannot stream, a coarser level is drawn."""

from __future__ import annotations

import numpy as np
import pytest

from volren.bricked.zarr_input import RENDERER_COPY_BYTES
from volren.io import ome_zarr_io
from volren.model.volume import UniformVolume

pytest.importorskip("zarr", reason="volren[zarr] is part of the test set-up")

SHAPE = (19, 26, 31)  # z, y, x: 15,314 voxels, 30,628 bytes of uint16


@pytest.fixture
def field_zarr(tmp_path):
    z, y, x = np.meshgrid(*(np.arange(n) for n in SHAPE), indexing="ij")
    values = (2000 + 1500 * np.sin(0.3 * x) * np.cos(0.25 * y) + 40 * z).astype(np.uint16)
    path = tmp_path / "field.zarr"
    ome_zarr_io.save_ome_zarr(UniformVolume(values, name="field"), path, chunk=8, levels=2)
    return path


def render_line(path, tmp_path, capsys, name, *flags) -> tuple[np.ndarray, str]:
    from volren.cli.main import main

    out = tmp_path / f"{name}.npy"
    assert main(["render", str(path), "--size", "20x16", *flags, "--save-array", str(out)]) == 0
    return np.load(out), capsys.readouterr()


def test_a_level_whose_values_fit_but_not_its_float_copy_is_streamed(field_zarr, tmp_path, capsys):
    voxels = int(np.prod(SHAPE))
    budget = 64 * 1024
    assert (
        voxels * 2 <= budget < voxels * (2 + RENDERER_COPY_BYTES["reference"])
    )  # the float64 copy does not fit
    flags = ["--renderer", "reference", "--level", "0"]
    streamed, said = render_line(field_zarr, tmp_path, capsys, "streamed", *flags, "--memory", "64KiB")
    assert "(field.zarr level 0 streamed:" in said.out
    whole, said = render_line(field_zarr, tmp_path, capsys, "whole", *flags)
    assert "(field.zarr level 0 in memory)" in said.out
    assert float(np.sqrt(np.mean((streamed.astype(np.float64) - whole) ** 2))) <= 1e-5


@pytest.mark.filterwarnings("default::volren.errors.VolrenWarning")  # the CLI prints it as one line
def test_a_renderer_that_cannot_stream_draws_the_finest_level_whose_copies_fit(field_zarr, tmp_path, capsys):
    flags = ["--renderer", "shearwarp", "--quality", "default"]
    _, said = render_line(field_zarr, tmp_path, capsys, "coarse", *flags, "--memory", "64KiB")
    assert "(field.zarr level 1 in memory)" in said.out
    assert ("field.zarr: its full resolution is 29.9 KiB (149.6 KiB drawn), more than the 64.0 KiB allowed; "
            "rendering level 1, the finest that fits (renderer shearwarp does not stream bricks)") in said.err  # fmt: skip
    from volren.cli.main import main

    assert main(["render", str(field_zarr), *flags, "--memory", "10KiB", "-o", str(tmp_path / "x.png")]) == 1
    assert ("field.zarr: --memory 10.0 KiB is too little for renderer shearwarp, which does not stream bricks: it takes "
            "17.1 KiB to draw even the coarsest level\n") in capsys.readouterr().err  # fmt: skip


def test_the_level_read_whole_is_the_finest_whose_values_and_renderer_copies_fit(field_zarr):
    """One count for `volren render` (a renderer that does not stream) and `volren view`."""
    from volren.bricked.zarr_input import MOST_COPY_BYTES, finest_level_read_whole

    image = ome_zarr_io.open_multiscale(field_zarr)
    budget = 128 * 1024
    voxels = [int(np.prod(level.shape)) for level in image.levels]
    assert (
        voxels[0] * (2 + RENDERER_COPY_BYTES["raycast"])
        <= budget
        < voxels[0] * (2 + RENDERER_COPY_BYTES["slicer"])
    )
    assert finest_level_read_whole(image, budget, "raycast") == 0
    assert finest_level_read_whole(image, budget, "slicer") == 1
    assert finest_level_read_whole(image, budget, "auto") == 1  # not chosen yet: the most copies
    assert finest_level_read_whole(image, voxels[1] * (2 + MOST_COPY_BYTES) - 1, "slicer") is None


def test_a_streamed_level_leaves_room_beside_its_chunk_cache_for_the_brick_being_drawn(tmp_path):
    """The chunk cache takes its share of --memory less what drawing one brick takes: the brick's
    voxels with two ghost layers a side, at the values' bytes and the renderer's copies', twice."""
    from volren.bricked.zarr_input import ZarrInput
    from volren.bricked.zarr_source import CACHE_SHARE
    from volren.model.camera import Camera

    values = np.zeros((40, 40, 40), dtype=np.uint16)
    values[::3] = 1000
    path = tmp_path / "slabs.zarr"
    ome_zarr_io.save_ome_zarr(UniformVolume(values, name="slabs"), path, chunk=16, levels=2)
    budget = 512 << 10
    zarr_input = ZarrInput(path, budget)
    frame = zarr_input.frame("reference", Camera.orbit(zarr_input.bounds), 16, 16, level=0)
    assert frame.source is not None  # 40^3 x (2 + 8) bytes drawn whole: more than 512 KiB
    brick = 2 * 20**3 * (2 + RENDERER_COPY_BYTES["reference"])
    assert frame.source.cache.budget == int(budget * CACHE_SHARE) - brick
