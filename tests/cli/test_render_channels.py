"""`volren render` and `volren movie` with a multi-channel volume: --channels (all or a pick),
--channel-tf, --channel-weight and --hide-channels, OME-Zarr channels, scene files with channels,
and one-line errors naming the flag."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
import pyvista as pv

from volren.cli.main import build_parser, main
from volren.cli.render_cmd import build_scene
from volren.io import save_scene, save_transfer_function
from volren.model.channels import ChannelTransferFunction
from volren.model.scene import Scene
from volren.model.transfer_function import TransferFunction1D
from volren.renderers.registry import registry

SHAPE = (6, 5, 4)  # z, y, x
RED = TransferFunction1D([[0, 1, 0, 0]], [[0, 0], [59, 0.7]], 2.0)


def field() -> np.ndarray:
    return np.arange(np.prod(SHAPE), dtype=np.float32).reshape(SHAPE) / 2


@pytest.fixture
def files(tmp_path):
    """rgb.vti (component c = field + 10 c), ct.vti (one component), red.json."""
    img = pv.ImageData(dimensions=SHAPE[::-1])
    img.point_data["rgb"] = np.stack([field().ravel() + 10 * c for c in range(3)], axis=1)
    img.save(tmp_path / "rgb.vti")
    one = pv.ImageData(dimensions=SHAPE[::-1])
    one.point_data["v"] = field().ravel()
    one.save(tmp_path / "ct.vti")
    save_transfer_function(RED, tmp_path / "red.json")
    return tmp_path


def scene_of(*argv: str) -> Scene:
    args = build_parser("render", every=False).parse_args(["render", *argv])
    return build_scene(args)[0]


def test_the_channel_flags_make_the_scene(files):
    scene = scene_of(str(files / "rgb.vti"), "--channels", "2,0", "--channel-tf", f"2={files / 'red.json'}",
                     "--channel-weight", "0=2.5", "--hide-channels", "0", "--quality", "draft")  # fmt: skip
    volume, tf = scene.volume, scene.transfer_function
    assert scene.channels == (2, 0) and volume.channels.indices == (2, 0)
    np.testing.assert_array_equal(volume.values, field() + 20)
    assert isinstance(tf, ChannelTransferFunction) and tf.tfs[0] == RED
    assert tf.weights == [1.0, 2.5] and tf.visible == [True, False]
    assert (
        registry.capabilities(scene.renderer).kinds["uniform"].channels and not scene.settings.preintegration
    )


def test_channels_alone_reads_every_component_and_tf_is_every_channels(files):
    scene = scene_of(str(files / "rgb.vti"), "--channels", "--tf", str(files / "red.json"))
    assert scene.channels is True and scene.volume.channels.count == 3
    assert [t.to_dict() for t in scene.transfer_function.tfs] == [RED.to_dict()] * 3
    plain = scene_of(str(files / "rgb.vti"))  # without --channels: the magnitude, as before
    assert plain.volume.channels is None and plain.volume.scalars == "rgb:magnitude"


def test_a_scene_file_keeps_its_channels_and_flags_go_over_them(files):
    tf = ChannelTransferFunction([RED, RED], weights=[1.0, 3.0])
    save_scene(Scene(str(files / "rgb.vti"), tf, renderer="reference", channels=(1, 2)), files / "s.json")
    again = scene_of("--scene", str(files / "s.json"), "--hide-channels", "2")
    assert again.volume.channels.indices == (1, 2) and again.channels == (1, 2)
    assert again.transfer_function.weights == [1.0, 3.0] and again.transfer_function.visible == [True, False]
    # INPUT given with the scene: read with the scene's pick
    given = scene_of("--scene", str(files / "s.json"), str(files / "rgb.vti"))
    assert given.volume.channels.indices == (1, 2)


@pytest.mark.parametrize(("flags", "message"), [
    (["--channels", "0,x"], "argument --channels: expected channels C,D,... (whole numbers from 0), got 'x'"),
    (["--channel-tf", "red.json"], "argument --channel-tf: expected C=TF.json"),
    (["--channel-tf", "x=red.json"], "argument --channel-tf: the channel before '=' must be a whole number"),
    (["--channel-weight", "1=-2"], "argument --channel-weight: the weight after '=' must be a number >= 0"),
    (["--channel-weight", "1=nan"], "argument --channel-weight: the weight after '=' must be a number >= 0"),
    (["--hide-channels", "-1"], "argument --hide-channels: expected channels C,D,..."),
])  # fmt: skip
def test_channel_flags_that_say_no_channel_are_usage_errors_naming_the_flag(capsys, flags, message):
    with pytest.raises(SystemExit) as exc:
        main(["render", "rgb.vti", "-o", "x.png", *flags])
    assert exc.value.code == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith(f"volren render: error: {message}")


def test_channel_inputs_that_cannot_be_used_are_one_line_errors_naming_the_flag(files, capsys):
    rgb, ct = str(files / "rgb.vti"), str(files / "ct.vti")
    (files / "seg.vti").write_bytes((files / "ct.vti").read_bytes())
    cases = [
        ([ct, "--channels"], f"--channels: {ct}: array 'v' has one component; channels come from an array"),
        ([rgb, "--channels", "0,5"], f"--channels: {rgb}: array 'rgb' has 3 components: channel 5 is not one of 0..2"),
        ([rgb, "--hide-channels", "1"], "--hide-channels: needs a multi-channel volume; rgb.vti is one field (give "
                                        "--channels)"),
        ([rgb, "--channels", "0", "--channel-weight", "1=2"], "--channel-weight: channel 1 is not drawn"),
        ([rgb, "--channels", "--channel-tf", f"1={files / 'none.json'}"], f"--channel-tf: {files / 'none.json'}: "
                                                                          "no such file"),
        ([rgb, "--channels", "--labels", str(files / "seg.vti")], "--channels: a volume is drawn with --labels or "
                                                                  "with --channels, not both at once yet"),
        ([rgb, "--channels", "--level", "1"], f"--level applies to an OME-Zarr INPUT (a .zarr folder or URL); {rgb}"),
        ([rgb, "--channels", "--preintegration"], "renderer reference has no pre-integration of several channels"),
    ]  # fmt: skip
    for argv, message in cases:
        assert main(["render", *argv, "-o", str(files / "x.png"), "--renderer", "reference"]) == 1, argv
        err = capsys.readouterr().err.splitlines()
        assert len(err) == 1 and err[0].startswith(f"volren: error: {message}"), (argv, err)


def test_an_ome_zarr_image_with_channels_is_read_whole_with_its_hints(tmp_path, capsys):
    zarr = pytest.importorskip("zarr", reason="volren[zarr] is part of the test set-up")
    group = zarr.open_group(str(tmp_path / "cells.zarr"), mode="w", zarr_format=2)
    values = np.stack([field(), field() + 100])
    group.create_array("0", shape=values.shape, chunks=(1, 3, 5, 4), dtype="float32")[:] = values
    group.attrs["multiscales"] = [{"version": "0.4", "axes": [{"name": a} for a in "czyx"],
                                   "datasets": [{"path": "0"}]}]  # fmt: skip
    group.attrs["omero"] = {
        "channels": [{"label": "DAPI", "color": "0000FF", "active": False}, {"label": "GFP"}]
    }
    scene = scene_of(str(tmp_path / "cells.zarr"), "--channels", "--channel-weight", "1=2")
    assert scene.volume.channels.names == ("DAPI", "GFP") and scene.volume.channels.colors[0] == (
        0.0,
        0.0,
        1.0,
    )
    np.testing.assert_array_equal(scene.volume.values, field() + 100)  # the first active channel
    assert scene.transfer_function.visible == [False, True] and scene.transfer_function.weights == [1.0, 2.0]
    # without --channels the streamed path refuses them, naming the flag to give
    assert main(["render", str(tmp_path / "cells.zarr"), "-o", str(tmp_path / "x.png")]) == 1
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and "axis 'c' holds 2 channels; pick them with --channels" in err[0]


@pytest.mark.skipif(not registry.capabilities("reference").kinds["uniform"].channels,
                    reason="reference does not mix channels yet")  # fmt: skip
def test_a_render_and_a_movie_with_channels(files, capsys):
    out = files / "rgb.png"
    argv = [
        str(files / "rgb.vti"),
        "--channels",
        "0,1",
        "--renderer",
        "reference",
        "--size",
        "8",
        "--quality",
        "draft",
    ]
    assert main(["render", *argv, "-o", str(out), "--save-array", str(files / "rgb.npy")]) == 0
    image = np.load(files / "rgb.npy")
    assert image.shape == (8, 8, 4) and image[..., 3].max() > 0
    assert main(["movie", *argv, "-o", str(files / "rgb.gif"), "--frames", "2"]) == 0


def test_the_channel_flags_import_nothing_heavy_when_the_parser_is_built():
    probe = ("import sys\nfrom volren.cli.main import build_parser\nbuild_parser('render', every=False)\n"
             "print(*(m for m in ('vtk', 'vtkmodules', 'pyvista', 'zarr', 'numba', 'dask') if m in sys.modules))")  # fmt: skip
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and done.stdout.split() == [], done.stderr


def test_the_scene_json_of_a_channel_scene(files):
    tf = ChannelTransferFunction([RED])
    save_scene(Scene(str(files / "rgb.vti"), tf, channels=(2,)), files / "one.json")
    assert json.loads((files / "one.json").read_text())["volume"]["channels"] == [2]


def test_a_movie_of_a_time_series_with_channels_is_refused_in_one_line(files, capsys):
    (files / "series").mkdir()
    for step in range(2):
        (files / "series" / f"rgb_{step}.vti").write_bytes((files / "rgb.vti").read_bytes())
    argv = [
        "movie",
        str(files / "series"),
        "--channels",
        "-o",
        str(files / "m.gif"),
        "--renderer",
        "reference",
    ]
    assert main(argv) == 1
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith(
        "volren: error: --channels: a time series' movie reads a volume a step"
    )
