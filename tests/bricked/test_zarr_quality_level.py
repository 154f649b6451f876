"""Which pyramid level an OME-Zarr frame draws: the full resolution at quality default, high and
exact (a block mean can drop a thin feature below the TF's threshold whatever the pixel size), the
level the view needs at draft and interactive (previews), the level named with --level always."""

from __future__ import annotations

import numpy as np
import pytest

from volren.bricked.zarr_source import level_for_view
from volren.io import ome_zarr_io
from volren.model.camera import Camera
from volren.model.volume import UniformVolume

pytest.importorskip("zarr", reason="volren[zarr] is part of the test set-up")

SIZE = 32


@pytest.fixture
def tube_zarr(tmp_path):
    """A 64^3 pyramid (`volren convert`) of a dim field crossed by a one-voxel-thin bright tube."""
    from volren.cli.main import main
    from volren.io import save_volume

    values = np.full((64, 64, 64), 100, dtype=np.uint16)
    values[:, 31, 31] = 4000
    source = tmp_path / "tube.vti"
    save_volume(UniformVolume(values, name="tube"), source)
    path = tmp_path / "tube.zarr"
    assert main(["convert", str(source), str(path), "--chunks", "16"]) == 0
    return path


def view_level(path) -> int:
    image = ome_zarr_io.open_multiscale(path)
    return level_for_view(image.levels, Camera.orbit(ome_zarr_io.load_level(path, 0).bounds), SIZE, SIZE)


def render(tmp_path, capsys, path, name, *flags) -> tuple[np.ndarray, str]:
    from volren.cli.main import main

    out = tmp_path / f"{name}.npy"
    argv = [
        "render",
        str(path),
        "--renderer",
        "slicer",
        "--size",
        str(SIZE),
        *flags,
        "--save-array",
        str(out),
    ]
    assert main(argv) == 0
    return np.load(out), capsys.readouterr().out


@pytest.mark.usefixtures("opengl")
def test_default_quality_draws_the_full_resolution_and_draft_the_level_the_view_needs(
    tube_zarr, tmp_path, capsys
):
    coarse = view_level(tube_zarr)
    assert coarse >= 1  # the view alone would draw a coarser level
    for quality in ("default", "high"):
        image, line = render(tmp_path, capsys, tube_zarr, quality, "--quality", quality)
        level_0, _ = render(tmp_path, capsys, tube_zarr, f"{quality}-0", "--quality", quality, "--level", "0")
        assert "(tube.zarr level 0 in memory)" in line
        np.testing.assert_array_equal(image, level_0)
    draft, line = render(tmp_path, capsys, tube_zarr, "draft", "--quality", "draft")
    named, _ = render(
        tmp_path, capsys, tube_zarr, "draft-named", "--quality", "draft", "--level", str(coarse)
    )
    assert f"(tube.zarr level {coarse} in memory)" in line
    np.testing.assert_array_equal(draft, named)


@pytest.mark.usefixtures("opengl")
def test_volren_render_from_python_takes_the_level_from_the_quality(tube_zarr):
    import volren

    flags = {"renderer": "slicer", "size": SIZE}
    np.testing.assert_array_equal(
        volren.render(str(tube_zarr), **flags), volren.render(str(tube_zarr), level=0, **flags)
    )
    np.testing.assert_array_equal(volren.render(str(tube_zarr), quality="interactive", **flags),
                                  volren.render(str(tube_zarr), quality="interactive", level=view_level(tube_zarr),
                                                **flags))  # fmt: skip


def test_a_cluster_frame_takes_the_level_from_the_quality(tube_zarr, monkeypatch):
    from volren.bricked import cluster
    from volren.bricked.zarr_input import ZarrInput

    drawn: list[int] = []

    class Recording:
        def __init__(self, client, spec, renderer, brick):
            drawn.append(spec.level)

        def render(self, *args):
            return np.zeros((SIZE, SIZE, 4), np.float32), None

        def close(self):
            pass

    class Client:
        def close(self):
            pass

    monkeypatch.setattr(cluster, "ClusterRenderer", Recording)
    monkeypatch.setattr(cluster, "local_client", lambda workers: Client())
    zarr_input = ZarrInput(tube_zarr)
    camera = Camera.orbit(zarr_input.bounds)
    for quality in ("default", "exact", "draft"):
        cluster.render_on_cluster("local:1", None, zarr_input, "reference", None, None, camera, SIZE, SIZE,
                                  quality=quality)  # fmt: skip
    assert drawn == [0, 0, view_level(tube_zarr)]
