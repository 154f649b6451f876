"""OME-Zarr images with a channel axis: the c axis read whole as channels (all, or those picked),
exactly as stored, with ``omero.channels``' labels, colours, windows and active flags; a time axis
of several entries and the streamed (bricked) path refused in one line."""

from __future__ import annotations

import math

import numpy as np
import pytest

from volren.errors import VolrenError, VolrenWarning
from volren.io import load_volume
from volren.io.channel_io import default_channel_tf

zarr = pytest.importorskip("zarr", reason="volren[zarr] is part of the test set-up")
from volren.io.ome_zarr_io import load_channels, open_multiscale  # noqa: E402

SHAPE = (3, 4, 5, 6)  # c, z, y, x
OMERO = {
    "channels": [
        {"label": "DAPI", "color": "0000FF", "window": {"start": 10, "end": 50, "min": 0, "max": 255},
         "active": False},
        {"label": "GFP", "color": "00ff00", "window": {"start": 5, "end": 1}, "active": True},
        {"color": "not a colour"},
    ]
}  # fmt: skip


def values_of(shape: tuple[int, ...]) -> np.ndarray:
    return np.arange(math.prod(shape), dtype=np.float32).reshape(shape)


def write(path, axes: str, shape: tuple[int, ...], omero=None, levels: int = 1) -> np.ndarray:
    """An OME-Zarr image of `axes` (ending zyx), bricks of 2 along z, and `levels` levels (each
    the first's every other voxel); returns level 0's values."""
    group = zarr.open_group(str(path), mode="w", zarr_format=2)
    full = values_of(shape)
    datasets = []
    for level in range(levels):
        step = 2**level
        data = full[(...,) + (slice(None, None, step),) * 3]
        chunks = (1,) * (len(shape) - 3) + (2,) + data.shape[-2:]
        group.create_array(str(level), shape=data.shape, chunks=chunks, dtype="float32")[:] = data
        scale = [1.0] * (len(shape) - 3) + [3.0 * step, 2.0 * step, 1.0 * step]
        datasets.append(
            {"path": str(level), "coordinateTransformations": [{"type": "scale", "scale": scale}]}
        )
    group.attrs["multiscales"] = [
        {"version": "0.4", "axes": [{"name": a} for a in axes], "datasets": datasets}
    ]
    if omero is not None:
        group.attrs["omero"] = omero
    return full


def test_every_channel_is_read_exactly_with_the_omero_hints(tmp_path):
    full = write(tmp_path / "cells.zarr", "czyx", SHAPE, OMERO)
    volume = load_volume(tmp_path / "cells.zarr", channels=True)
    channels = volume.channels
    assert np.array_equal(channels.values, full) and volume.spacing == (1.0, 2.0, 3.0)
    assert channels.names == ("DAPI", "GFP", "channel 2")
    assert channels.colors == ((0.0, 0.0, 1.0), (0.0, 1.0, 0.0), None)
    assert channels.windows == ((10.0, 50.0), None, None)  # end <= start: not a window
    assert channels.active == (False, True, True)
    # the values are the first active channel's, a view of the channels' array
    assert np.array_equal(volume.values, full[1]) and np.shares_memory(volume.values, channels.values)
    tf = default_channel_tf(channels)
    assert tf.visible == [False, True, True]
    _, alpha = tf.tfs[0].sample(np.array([10.0, 50.0]))
    assert np.allclose(alpha, [0.0, 0.2])  # the ramp spans the omero window


def test_a_pick_reads_those_channels_in_its_order_and_a_singleton_time_axis_is_dropped(tmp_path):
    full = write(tmp_path / "tc.zarr", "tczyx", (1, *SHAPE), OMERO)
    volume = load_volume(tmp_path / "tc.zarr", channels=[2, 0])
    assert np.array_equal(volume.channels.values, full[0, [2, 0]])
    assert volume.channels.indices == (2, 0) and volume.channels.names == ("channel 2", "DAPI")
    assert np.array_equal(volume.values, full[0, 2])  # channel 2 is active, DAPI not


def test_memory_picks_the_finest_level_the_picked_channels_fit_in(tmp_path):
    full = write(tmp_path / "two.zarr", "czyx", (2, 4, 6, 8), levels=2)
    one_level = 4 * 6 * 8 * 4  # bytes of one channel at level 0
    with pytest.warns(VolrenWarning, match=r"rendering level 1, the finest that fits \(2 channels\)"):
        coarse = load_channels(tmp_path / "two.zarr", True, memory=2 * one_level - 1)
    assert np.array_equal(coarse.channels.values, full[:, ::2, ::2, ::2]) and coarse.spacing == (
        2.0,
        4.0,
        6.0,
    )
    fine = load_channels(tmp_path / "two.zarr", [1], memory=one_level)
    assert np.array_equal(fine.channels.values, full[[1]])
    with pytest.raises(VolrenError, match=r"no level 5; the image has levels 0 to 1"):
        load_channels(tmp_path / "two.zarr", True, level=5)


def test_channels_without_asking_time_points_and_images_without_c_are_one_line(tmp_path):
    write(tmp_path / "cells.zarr", "czyx", SHAPE)
    for read in (
        lambda: load_volume(tmp_path / "cells.zarr"),
        lambda: open_multiscale(tmp_path / "cells.zarr"),
    ):
        with pytest.raises(
            VolrenError, match=r"axis 'c' holds 3 channels; pick them with --channels"
        ) as info:
            read()
        assert "\n" not in str(info.value)
    write(tmp_path / "time.zarr", "tczyx", (2, *SHAPE))
    with pytest.raises(VolrenError, match=r"axis 't' holds 2 time points; volren reads one time point"):
        load_volume(tmp_path / "time.zarr", channels=True)
    write(tmp_path / "plain.zarr", "zyx", SHAPE[1:])
    with pytest.raises(VolrenError, match=r"has no channel axis \(c\); it holds one field"):
        load_volume(tmp_path / "plain.zarr", channels=True)
    with pytest.raises(VolrenError, match=r"channel 3 is not one of 0..2"):
        load_volume(tmp_path / "cells.zarr", channels=[3])
