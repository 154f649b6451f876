"""OME-Zarr pyramids (issue 24, the format): written and read back exactly, block means and brick
ranges against oracles computed here, ome-zarr-py reading what volren writes, and bad input."""

from __future__ import annotations

import json
import math
import shutil

import numpy as np
import pytest

from volren.errors import VolrenError, VolrenWarning
from volren.io import load_volume
from volren.model.volume import UniformVolume

zarr = pytest.importorskip("zarr", reason="volren[zarr] is part of the test set-up")
from volren.io.ome_zarr_io import load_level, open_multiscale, save_ome_zarr  # noqa: E402


@pytest.fixture
def volume() -> UniformVolume:
    rng = np.random.default_rng(7)
    values = rng.integers(0, 4000, size=(21, 30, 37), dtype=np.uint16)  # odd sides: trimmed when halved
    return UniformVolume(values, spacing=(0.5, 0.75, 2.0), origin=(1.0, -2.0, 3.0), name="cells")


def mean_oracle(values: np.ndarray) -> np.ndarray:
    """2x2x2 block means by explicit loops over the trimmed grid, rounded as uint16."""
    nz, ny, nx = (n // 2 for n in values.shape)
    out = np.empty((nz, ny, nx), values.dtype)
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                block = values[2 * k : 2 * k + 2, 2 * j : 2 * j + 2, 2 * i : 2 * i + 2].astype(np.float64)
                out[k, j, i] = np.rint(block.mean())
    return out


def test_a_pyramid_round_trips_with_block_means_placement_and_brick_ranges(tmp_path, volume):
    path = tmp_path / "cells.zarr"
    assert save_ome_zarr(volume, path, chunk=8, levels=3) == 3
    image = open_multiscale(path)
    assert [level.shape for level in image.levels] == [(21, 30, 37), (10, 15, 18), (5, 7, 9)]
    whole = load_level(path, 0)
    np.testing.assert_array_equal(whole.values, volume.values)
    assert whole.spacing == volume.spacing and whole.origin == volume.origin and whole.name == "cells"
    coarse = load_level(path, 1)
    np.testing.assert_array_equal(coarse.values, mean_oracle(volume.values))
    assert coarse.spacing == (1.0, 1.5, 4.0) and coarse.origin == (1.25, -1.625, 4.0)  # centred in its block
    np.testing.assert_array_equal(load_level(path, 2).values, mean_oracle(mean_oracle(volume.values)))
    for level, ranges in enumerate(image.brick_ranges):
        values = load_level(path, level).values
        counts = [math.ceil(n / 8) for n in values.shape]
        assert len(ranges) == math.prod(counts)
        for flat, index in enumerate(np.ndindex(*counts)):
            brick = values[tuple(slice(8 * k, 8 * k + 8) for k in index)]
            assert ranges[flat] == (float(brick.min()), float(brick.max())), (level, index)


def test_ome_zarr_py_reads_what_volren_writes(tmp_path, volume):
    reader = pytest.importorskip("ome_zarr.reader")
    from ome_zarr.io import parse_url

    path = tmp_path / "cells.zarr"
    save_ome_zarr(volume, path, chunk=16)
    node = next(iter(reader.Reader(parse_url(str(path)))()))
    assert len(node.data) == len(open_multiscale(path).levels)
    for level, data in enumerate(node.data):
        np.testing.assert_array_equal(np.asarray(data), load_level(path, level).values)
    datasets = node.metadata["coordinateTransformations"]
    assert datasets[1][0]["scale"] == [4.0, 1.5, 1.0]  # z, y, x


def test_load_volume_and_render_take_an_ome_zarr_folder(tmp_path, volume):
    import volren

    path = tmp_path / "cells.zarr"
    save_ome_zarr(volume, path, chunk=16)
    loaded = load_volume(path)
    np.testing.assert_array_equal(loaded.values, volume.values)
    tf = {
        "version": 1,
        "kind": "1d",
        "color": [[0, 0.2, 0.4, 1], [4000, 1, 0.8, 0.1]],
        "opacity": [[0, 0], [4000, 0.6]],
        "opacity_unit_distance": 4.0,
    }
    kwargs = dict(renderer="reference", size=(12, 10), quality=None, step=1.0, tf=tf)
    np.testing.assert_array_equal(volren.render(path, level=0, **kwargs), volren.render(volume, **kwargs))
    # without a level or a TF: the level the view needs, and the default TF of the coarsest level
    thumbnail = volren.render(path, renderer="reference", size=(12, 10))
    assert thumbnail[..., 3].max() > 0.05


def test_nan_stays_out_of_brick_ranges(tmp_path):
    values = np.arange(4 * 4 * 8, dtype=np.float32).reshape(4, 4, 8)
    values[:, :, 4:] = np.nan  # the second brick along x has no finite value
    values[0, 0, 0] = np.nan
    path = tmp_path / "nan.zarr"
    save_ome_zarr(UniformVolume(values), path, chunk=4, levels=1)
    assert open_multiscale(path).brick_ranges[0] == ((1.0, float(values[3, 3, 3])), None)


def corrupt_chunk(path, level: str = "0") -> str:
    chunk = sorted(p for p in (path / level).iterdir() if not p.name.startswith("."))[1]
    chunk.write_bytes(b"this is not a compressed chunk")
    return chunk.name


def test_bad_images_are_one_line_errors_naming_the_part(tmp_path, volume):
    path = tmp_path / "cells.zarr"
    save_ome_zarr(volume, path, chunk=8, levels=2)
    name = corrupt_chunk(path)
    with pytest.raises(VolrenError, match=rf"cells.zarr: level '0', brick {name}: cannot be read") as exc:
        load_volume(path)
    assert "\n" not in str(exc.value)
    shutil.rmtree(path / "1")
    with pytest.raises(VolrenError, match="cells.zarr: level '1' is listed but missing"):
        open_multiscale(path)
    with pytest.raises(VolrenError, match="no level 5; the image has levels 0 to 1"):
        save_ome_zarr(volume, tmp_path / "ok.zarr", chunk=8, levels=2) and load_level(tmp_path / "ok.zarr", 5)
    attrs = json.loads((tmp_path / "ok.zarr" / ".zattrs").read_text())
    attrs["volren"]["brick_ranges"][0] = attrs["volren"]["brick_ranges"][0][:-1]
    (tmp_path / "ok.zarr" / ".zattrs").write_text(json.dumps(attrs))
    with pytest.raises(VolrenError, match=r"level '0': its chunk shape \(8, 8, 8\) makes 60 bricks, the stored ranges "
                       "are for 59"):  # fmt: skip
        open_multiscale(tmp_path / "ok.zarr")
    plain = zarr.open_group(str(tmp_path / "plain.zarr"), mode="w", zarr_format=2)
    plain.create_array("0", shape=(4, 4, 4), dtype="uint8")
    with pytest.raises(VolrenError, match="plain.zarr: not an OME-Zarr image: no 'multiscales'"):
        load_volume(tmp_path / "plain.zarr")
    with pytest.raises(VolrenError, match="holds one field; there is no array 'density'"):
        load_volume(path, "density")


def test_an_absent_chunk_reads_as_the_fill_value(tmp_path, volume):
    path = tmp_path / "cells.zarr"
    save_ome_zarr(volume, path, chunk=8, levels=1)
    (path / "0" / "0.0.0").unlink()
    values = load_level(path).values
    assert not values[:8, :8, :8].any() and np.array_equal(values[8:], volume.values[8:])


def test_time_and_channel_axes_with_one_entry_are_read_and_more_are_refused(tmp_path):
    for name, shape in (("one.zarr", (1, 1, 4, 5, 6)), ("two.zarr", (1, 2, 4, 5, 6))):
        group = zarr.open_group(str(tmp_path / name), mode="w", zarr_format=2)
        array = group.create_array("0", shape=shape, chunks=(1, 1, 4, 5, 6), dtype="float32")
        array[:] = np.arange(math.prod(shape), dtype=np.float32).reshape(shape)
        group.attrs["multiscales"] = [
            {
                "version": "0.4",
                "axes": [{"name": a} for a in "tczyx"],
                "datasets": [
                    {"path": "0", "coordinateTransformations": [{"type": "scale", "scale": [1, 1, 3, 2, 1]}]}
                ],
            }
        ]
    one = load_volume(tmp_path / "one.zarr")
    assert one.dimensions == (6, 5, 4) and one.spacing == (1.0, 2.0, 3.0)
    with pytest.raises(VolrenError, match=r"axis 'c' holds 2 channels; pick them with --channels"):
        load_volume(tmp_path / "two.zarr")


def test_a_level_too_large_for_memory_is_refused_naming_one_that_fits(tmp_path, volume, monkeypatch):
    from volren.io import ome_zarr_io

    path = tmp_path / "cells.zarr"
    save_ome_zarr(volume, path, chunk=8, levels=3)
    monkeypatch.setattr(ome_zarr_io, "MAX_IN_MEMORY_BYTES", 2 * 15 * 10 * 18)
    with pytest.raises(
        VolrenError, match="level 0 is 45.5 KiB, more than the 5.3 KiB allowed read whole; level 1 fits"
    ):
        load_level(path, 0)


def test_volren_convert_writes_the_pyramid_and_refuses_what_it_cannot(tmp_path, capsys, volume):
    from volren.cli.main import main
    from volren.io import save_volume

    source = tmp_path / "cells.vti"
    save_volume(volume, source)
    out = tmp_path / "cells.zarr"
    assert main(["convert", str(source), str(out), "--chunks", "16"]) == 0
    assert capsys.readouterr().out.strip() == f"{source}: 37x30x21 uint16 -> {out} (3 levels, 16^3 bricks)"
    np.testing.assert_array_equal(load_volume(out).values, volume.values)
    for argv, message in (
        ([str(source), str(out)], "exists; add --force"),
        ([str(source), str(tmp_path / "cells.ome")], "a folder named *.zarr"),
        (
            [str(source), str(out), "--force", "--levels", "9"],
            "--levels 9 is too many: its 37x30x21 grid has at most 4",
        ),
    ):
        assert main(["convert", *argv]) == 1
        assert message in capsys.readouterr().err
    np.testing.assert_array_equal(load_volume(out).values, volume.values)  # a failed --force kept the old one


@pytest.mark.vtk
@pytest.mark.filterwarnings("default::volren.errors.VolrenWarning")  # the CLI prints it as one line
def test_the_level_drawn_is_the_finest_within_the_memory_allowed(tmp_path, volume, capsys):
    """Issue 24, out of core on one machine (its first step): --memory bounds what is read, and the
    finest level within it is drawn, saying so in one line; --level names one."""
    from volren.cli.main import main
    from volren.io.volume_io import load_ome_zarr

    path = tmp_path / "cells.zarr"
    save_ome_zarr(volume, path, chunk=8, levels=3)
    level_1 = load_level(path, 1)
    with pytest.warns(VolrenWarning, match="cells.zarr: its full resolution is 45.5 KiB, more than the 20.0 KiB "
                      "allowed; rendering level 1, the finest that fits"):  # fmt: skip
        chosen = load_ome_zarr(path, memory=20 * 1024)
    np.testing.assert_array_equal(chosen.values, level_1.values)
    flags = ["--renderer", "vtk", "--size", "16", "--quality", "default"]
    assert main(["render", str(path), "--level", "1", *flags, "--save-array", str(tmp_path / "a.npy")]) == 0
    capsys.readouterr()
    assert (
        main(["render", str(path), "--memory", "20KiB", *flags, "--save-array", str(tmp_path / "b.npy")]) == 0
    )
    assert "volren: warning: cells.zarr: its full resolution is 45.5 KiB" in capsys.readouterr().err
    np.testing.assert_array_equal(np.load(tmp_path / "a.npy"), np.load(tmp_path / "b.npy"))
    assert main(["render", str(path), *flags, "--memory", "500", "-o", str(tmp_path / "x.png")]) == 1
    assert ": --memory 500 bytes is too little; this image needs at least 1.3 KiB (its coarsest level read whole, and a " \
           "chunk in the chunk cache)" in capsys.readouterr().err  # fmt: skip
    assert main(["render", str(path), *flags, "--level", "7", "-o", str(tmp_path / "x.png")]) == 1
    assert "no level 7; the image has levels 0 to 2" in capsys.readouterr().err


def test_a_server_that_does_not_answer_is_a_one_line_error(monkeypatch):
    """Bad input: no hang on an unreachable or silent server. The reader's HTTP client waits
    `URL_TIMEOUT_S` to connect and between packets, then says so in one line (how long giving up
    takes: `python -m benchmarks.give_up_times`)."""
    from volren.io import ome_zarr_io
    from volren.testing.silent_server import silent_server

    monkeypatch.setattr(ome_zarr_io, "URL_TIMEOUT_S", 1.0)
    with silent_server() as port:
        url = f"http://127.0.0.1:{port}/image.zarr"
        limits = ome_zarr_io._store_options(url)["storage_options"]["client_kwargs"]["timeout"]
        assert (limits.total, limits.connect, limits.sock_read) == (None, 1.0, 1.0)
        with pytest.raises(VolrenError, match="image.zarr: the server did not answer within 1 s") as exc:
            load_volume(url)
    assert "\n" not in str(exc.value)
