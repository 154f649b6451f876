"""OME-Zarr images with a time axis: a time series (`volren.io.series_io`) whose steps,
``image.zarr#t=N``, read that time point alone (whole, streamed by bricks, or its channels),
exactly as stored, at the times the t axis' scale and translation give; one-line errors otherwise."""

from __future__ import annotations

import math

import numpy as np
import pytest

from volren.errors import VolrenError
from volren.io import load_volume
from volren.io.series_io import is_series, load_series

zarr = pytest.importorskip("zarr", reason="volren[zarr] is part of the test set-up")
from volren.io.ome_zarr_io import open_multiscale, read_brick, split_time_point  # noqa: E402

T_SCALE, T_START = 2.5, 1.0


def write(path, axes: str, shape: tuple[int, ...]) -> np.ndarray:
    """An OME-Zarr image of `axes` (ending zyx), one time point and channel per brick and bricks of 2
    along z; the t axis at T_START + T_SCALE * k. Returns its values, each distinct."""
    group = zarr.open_group(str(path), mode="w", zarr_format=2)
    full = np.arange(math.prod(shape), dtype=np.float32).reshape(shape)
    chunks = (1,) * (len(shape) - 3) + (2, *shape[-2:])
    group.create_array("0", shape=shape, chunks=chunks, dtype="float32")[:] = full
    lead = [T_SCALE if a == "t" else 1.0 for a in axes[:-3]]
    shift = [T_START if a == "t" else 0.0 for a in axes[:-3]]
    transforms = [{"type": "scale", "scale": [*lead, 3.0, 2.0, 1.0]},
                  {"type": "translation", "translation": [*shift, 0.0, 0.0, 0.0]}]  # fmt: skip
    group.attrs["multiscales"] = [{"version": "0.4", "axes": [{"name": a} for a in axes],
                                   "datasets": [{"path": "0", "coordinateTransformations": transforms}]}]  # fmt: skip
    return full


def test_a_t_axis_is_a_time_series_each_step_read_exactly(tmp_path):
    path = tmp_path / "movie.zarr"
    full = write(path, "tzyx", (4, 4, 5, 6))
    assert is_series(path)
    series = load_series(path)
    assert series.times == (1.0, 3.5, 6.0, 8.5)
    assert [str(s) for s in series.steps] == [f"{path}#t={k}" for k in range(4)]
    assert series.label(2) == "step 3 of 4 (t = 6, movie.zarr#t=2)"
    for k, step in enumerate(series.steps):
        volume = load_volume(step)
        assert np.array_equal(volume.values, full[k]) and volume.spacing == (1.0, 2.0, 3.0)


def test_channels_and_time_together(tmp_path):
    path = tmp_path / "cells.zarr"
    full = write(path, "tczyx", (3, 2, 4, 5, 6))
    series = load_series(path)
    assert len(series) == 3
    volume = load_volume(series.steps[1], channels=[1, 0])
    assert np.array_equal(volume.channels.values, full[1, [1, 0]])
    with pytest.raises(VolrenError, match=r"axis 'c' holds 2 channels; pick them with --channels"):
        load_volume(series.steps[1])


def test_the_streamed_path_reads_the_named_time_point(tmp_path):
    path = tmp_path / "movie.zarr"
    full = write(path, "tzyx", (3, 4, 5, 6))
    image = open_multiscale(f"{path}#t=2")
    assert image.time == 2 and image.times == (1.0, 3.5, 6.0) and image.path == str(path)
    brick = read_brick(image, 0, image.array(0), (1, 0, 0))
    assert np.array_equal(brick, full[2, 2:4])


def test_only_the_time_point_asked_for_is_read(tmp_path):
    """Time point 0's bricks made unreadable: the others still read, and 0 names its brick."""
    path = tmp_path / "movie.zarr"
    full = write(path, "tzyx", (2, 4, 5, 6))
    for brick in (path / "0").glob("0.*"):
        brick.write_bytes(b"not a brick")
    assert np.array_equal(load_volume(f"{path}#t=1").values, full[1])
    with pytest.raises(VolrenError, match=r"level '0', brick 0.0.0: cannot be read"):
        load_volume(f"{path}#t=0")


def test_one_line_errors_and_images_that_are_not_series(tmp_path):
    path = tmp_path / "movie.zarr"
    write(path, "tzyx", (3, 4, 5, 6))
    with pytest.raises(
        VolrenError, match=r"axis 't' holds 3 time points; .* name one as IMAGE.zarr#t=N"
    ) as info:
        load_volume(path)
    assert "\n" not in str(info.value)
    with pytest.raises(VolrenError, match=r"movie.zarr: no time point 3; the image has time points 0 to 2"):
        load_volume(f"{path}#t=3")
    write(tmp_path / "one.zarr", "tzyx", (1, 4, 5, 6))
    write(tmp_path / "still.zarr", "zyx", (4, 5, 6))
    assert not is_series(tmp_path / "one.zarr") and not is_series(tmp_path / "still.zarr")
    assert load_volume(f"{tmp_path / 'still.zarr'}#t=0").dimensions == (6, 5, 4)
    # a folder whose own name ends like a time point is that folder, not a time point of another
    odd = tmp_path / "odd.zarr#t=1"
    write(odd, "zyx", (4, 5, 6))
    assert split_time_point(odd) == (str(odd), None)
    assert load_volume(odd).dimensions == (6, 5, 4)


def test_ome_zarr_package_images_with_a_time_axis(tmp_path):
    writer = pytest.importorskip("ome_zarr.writer")
    values = np.arange(3 * 4 * 5 * 6, dtype=np.uint16).reshape(3, 4, 5, 6)
    group = zarr.open_group(str(tmp_path / "ome.zarr"), mode="w")
    writer.write_image(values, group, axes="tzyx", scale_factors=[])
    series = load_series(tmp_path / "ome.zarr")
    assert series.times == (0.0, 1.0, 2.0)
    assert np.array_equal(load_volume(series.steps[2]).values, values[2])


def test_render_draws_the_time_step_asked_for(tmp_path):
    from volren.cli.main import build_parser
    from volren.cli.render_cmd import build_scene

    path = tmp_path / "movie.zarr"
    full = write(path, "tzyx", (3, 4, 5, 6))
    args = build_parser("render", every=False).parse_args(["render", str(path), "--time-step", "2"])
    _scene, _why, source = build_scene(args)
    image = source.image.image  # the streamed input's opened image (`ZarrInput.image`)
    assert image.time == 2
    assert np.array_equal(read_brick(image, 0, image.array(0), (0, 0, 0)), full[2, :2])
