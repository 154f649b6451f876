"""2D transfer functions through `volren render --tf` and `volren.render`: drawn by the
reference renderer, refused by vtk in one line."""

from __future__ import annotations

import numpy as np
import pytest

import volren
from volren.cli.main import main
from volren.io import save_transfer_function, save_volume
from volren.model import TFWidget, TransferFunction2D, UniformVolume


@pytest.fixture
def files(tmp_path):
    x = np.arange(5) * 0.5
    values = np.broadcast_to(2.0 * x, (4, 3, 5)).astype(np.float32)  # s = 2 x: |grad s| = 2
    volume = UniformVolume(np.ascontiguousarray(values), spacing=(0.5, 0.5, 0.5))
    save_volume(volume, tmp_path / "ramp.vti")
    tf = TransferFunction2D(
        (0.0, 4.0), (0.0, 3.0), [TFWidget.box((0.5, 3.5), (1.5, 2.5), (1.0, 0.5, 0.0), 0.6)]
    )
    save_transfer_function(tf, tmp_path / "tf2d.json")
    return tmp_path, tf


def test_render_with_a_2d_tf_file(files, capsys):
    folder, tf = files
    npy = folder / "out.npy"
    args = ["render", str(folder / "ramp.vti"), "--tf", str(folder / "tf2d.json"), "--renderer", "reference",
            "--size", "12", "--azimuth", "20", "-o", str(folder / "out.png"), "--save-array", str(npy)]  # fmt: skip
    assert main(args) == 0
    out = capsys.readouterr().out.strip().splitlines()
    assert len(out) == 1 and out[0].startswith("reference: 12x12 in ")
    image = np.load(npy)
    assert image[..., 3].max() > 0.3
    api = volren.render(folder / "ramp.vti", tf, renderer="reference", size=12, azimuth=20)
    assert np.array_equal(api, image)
    assert np.array_equal(
        volren.render(folder / "ramp.vti", tf.to_dict(), renderer="reference", size=12, azimuth=20), image
    )


def test_vtk_refuses_a_2d_tf_file_in_one_line(files, capsys):
    folder, _ = files
    code = main(
        [
            "render",
            str(folder / "ramp.vti"),
            "--tf",
            str(folder / "tf2d.json"),
            "-o",
            str(folder / "x.png"),
            "--renderer",
            "vtk",
        ]
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1 and len(err) == 1, err
    assert err[0] == "volren: error: renderer vtk does not support 2D transfer functions on uniform volumes"
