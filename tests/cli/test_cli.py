"""`volren` on the command line: in process and as a subprocess, good and bad input."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from volren.cli.main import main
from volren.model.transfer_function import TransferFunction1D
from volren.renderers.registry import registry
from volren.samples import sample_paths

pytestmark = pytest.mark.usefixtures("opengl")


@pytest.fixture(scope="module")
def ml_sample():
    return sample_paths("marschner_lobb")


def test_renderers_lists_the_builtins_with_capabilities(capsys):
    assert main(["renderers"]) == 0
    out = capsys.readouterr().out
    assert "vtk" in out and "reference" in out and "uniform" in out and "tet" in out


def test_render_writes_png_and_array_and_prints_one_line(tmp_path, capsys, ml_sample):
    volume, tf = ml_sample
    png, npy = tmp_path / "out.png", tmp_path / "out.npy"
    code = main(
        [
            "render",
            str(volume),
            "--tf",
            str(tf),
            "-o",
            str(png),
            "--size",
            "40x30",
            "--azimuth",
            "30",
            "--elevation",
            "20",
            "--save-array",
            str(npy),
        ]
    )
    assert code == 0
    out = capsys.readouterr().out.strip().splitlines()
    # no --renderer: `auto` names its choice and why
    name, _, rest = out[0].partition(" (auto: ")
    assert len(out) == 1 and name in registry.names() and "): 40x30 in " in rest and "ms" in rest
    assert Image.open(png).size == (40, 30)
    array = np.load(npy)
    assert array.shape == (30, 40, 4) and array.dtype == np.float32
    # The PNG is the array over black, 8 bits.
    pixels = np.asarray(Image.open(png).convert("RGB"), dtype=float) / 255
    assert np.abs(pixels - np.clip(array[..., :3], 0, 1)).max() <= 1 / 255 + 1e-6
    # The same through the Python API.
    import volren

    api = volren.render(volume, tf, size=(40, 30), azimuth=30, elevation=20)
    assert np.array_equal(api, array)


@pytest.mark.vtk
def test_scene_file_and_flag_overrides(tmp_path, capsys, ml_sample):
    volume, tf = ml_sample
    scene = {
        "version": 1,
        "volume": {"path": str(volume)},
        "transfer_function": json.loads(Path(tf).read_text()),
        "camera": {"azimuth": 30, "elevation": 20, "zoom": 1.2},
        "settings": {"step": 0.5},
        "renderer": "vtk",
        "quality": "default",
        "size": [24, 24],
    }
    scene_path = tmp_path / "scene.json"
    scene_path.write_text(json.dumps(scene))
    assert main(["render", "--scene", str(scene_path), "--save-array", str(tmp_path / "a.npy")]) == 0
    assert (
        main(
            [
                "render",
                "--scene",
                str(scene_path),
                "--size",
                "16",
                "--azimuth",
                "120",
                "--save-array",
                str(tmp_path / "b.npy"),
            ]
        )
        == 0
    )
    a, b = np.load(tmp_path / "a.npy"), np.load(tmp_path / "b.npy")
    assert a.shape == (24, 24, 4) and b.shape == (16, 16, 4)
    direct = tmp_path / "c.npy"
    assert (
        main(
            [
                "render",
                str(volume),
                "--tf",
                str(tf),
                "--size",
                "24",
                "--azimuth",
                "30",
                "--renderer",
                "vtk",
                "--elevation",
                "20",
                "--zoom",
                "1.2",
                "--save-array",
                str(direct),
            ]
        )
        == 0
    )
    assert np.array_equal(a, np.load(direct))
    capsys.readouterr()


@pytest.mark.vtk
def test_a_scene_naming_a_time_series_renders_its_step(tmp_path, capsys):
    """A scene's "time_series" (what the app saves on a step of a series) names the volume: the
    step's file of the series, as `volren render SERIES --time-step N` draws it."""
    from tests.app.test_time_series import write_pvd, write_steps

    steps = write_steps(tmp_path, 3)
    pvd = write_pvd(tmp_path / "run.pvd", [(k, p.name) for k, p in enumerate(steps)])
    tf = TransferFunction1D.ramp(0, 3, 0.8).to_dict()
    scene_path = tmp_path / "scene.json"
    scene_path.write_text(json.dumps({"version": 1, "time_series": {"path": "run.pvd", "step": 2},
                                      "transfer_function": tf, "renderer": "vtk", "quality": "default", "size": [16, 16]}))  # fmt: skip
    (tmp_path / "tf.json").write_text(json.dumps(tf))
    assert main(["render", "--scene", str(scene_path), "--save-array", str(tmp_path / "scene.npy")]) == 0
    assert main(["render", str(pvd), "--time-step", "2", "--tf", str(tmp_path / "tf.json"), "--renderer", "vtk",
                 "--size", "16", "--save-array", str(tmp_path / "step.npy")]) == 0  # fmt: skip
    np.testing.assert_array_equal(np.load(tmp_path / "scene.npy"), np.load(tmp_path / "step.npy"))
    capsys.readouterr()


@pytest.mark.parametrize(
    "args, message",
    [
        (["render", "{missing}", "-o", "{out}"], "missing.vti"),
        (["render", "{volume}", "-o", "{out}", "--renderer", "nope"], "unknown renderer 'nope'"),
        (["render", "{volume}", "-o", "{out}", "--tf", "{missing}"], "missing.vti"),
        (
            ["render", "{volume}", "-o", "{out}", "--renderer", "vtk", "--option", "mapper=warp"],
            "renderer vtk: option mapper must be one of 'auto'",
        ),
        (["render", "{volume}", "-o", "{out}", "--option", "mapper=warp"], "--option mapper: renderer "),
        (["render", "{volume}", "-o", "{tmp}/no/such/dir/x.png"], "does not exist"),
        (["render", "{volume}"], "-o OUT.png"),
        (["render", "-o", "{out}"], "INPUT"),
    ],
)
def test_bad_input_gives_one_line_and_exit_1(tmp_path, capsys, ml_sample, args, message):
    fill = {
        "missing": str(tmp_path / "missing.vti"),
        "out": str(tmp_path / "x.png"),
        "volume": str(ml_sample[0]),
        "tmp": str(tmp_path),
    }
    code = main([a.format(**fill) for a in args])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1
    assert len(err) == 1 and err[0].startswith("volren: error: ") and message in err[0], err


def run_cli(*args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONWARNINGS="ignore")
    return subprocess.run(
        [sys.executable, "-m", "volren.cli.main", *args], capture_output=True, text=True, timeout=120, env=env
    )


def test_subprocess_missing_file_is_one_line_and_nonzero(tmp_path):
    result = run_cli("render", str(tmp_path / "nothing.nrrd"), "-o", str(tmp_path / "x.png"))
    assert result.returncode == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "nothing.nrrd" in lines[0] and "Traceback" not in result.stderr


def test_subprocess_render_and_console_script(tmp_path, ml_sample):
    result = run_cli("render", str(ml_sample[0]), "-o", str(tmp_path / "x.png"), "--size", "16")
    assert result.returncode == 0, result.stderr
    assert " (auto: " in result.stdout and "): 16x16 in " in result.stdout
    script = Path(sys.executable).parent / "volren"
    if script.exists():
        version = subprocess.run([str(script), "--version"], capture_output=True, text=True, timeout=60)
        assert version.stdout.startswith("volren ")


@pytest.mark.parametrize(
    "argv, names",
    [
        (["render", "--blend", "xray"], ["volren render: error:", "--blend", "xray"]),
        (["render", "--zoom", "big"], ["volren render: error:", "--zoom", "big"]),
        (["render", "--no-such-flag"], ["volren: error:", "unrecognized arguments: --no-such-flag"]),
        (["nosuch"], ["volren: error:", "nosuch"]),
        (["bench", "run", "--size"], ["volren bench run: error:", "--size"]),
    ],
)
def test_usage_errors_are_one_line_naming_the_flag_and_exit_2(capsys, argv, names):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and all(n in err[0] for n in names) and "--help" in err[0], err


@pytest.mark.vtk
def test_demo_renders_every_sample_with_each_renderer(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path), "--size", "24", "--renderers", "vtk"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 3 and all("ms per frame" in line for line in lines)
    assert sorted(p.name for p in tmp_path.glob("*.png")) == [
        "hollow_cylinder_vtk.png",
        "marschner_lobb_vtk.png",
        "phantom_ct_vtk.png",
    ]


@pytest.mark.parametrize(
    "extra, message",
    [
        (
            ["--raw-spacing", "2,2,2"],
            "--raw-spacing describes headerless raw data only (it needs --raw-shape)",
        ),
        (["--raw-dtype", "int16"], "--raw-dtype describes headerless raw data only"),
        (["--raw-byte-order", "big"], "--raw-byte-order describes headerless raw data only"),
    ],
)
def test_raw_flags_on_a_file_with_a_header_are_refused_not_ignored(
    tmp_path, capsys, ml_sample, extra, message
):
    assert main(["render", str(ml_sample[0]), "-o", str(tmp_path / "x.png"), *extra]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0] and str(ml_sample[0]) in err[0], err


def test_headerless_raw_without_a_shape_names_the_flags(tmp_path, capsys):
    raw = tmp_path / "d.raw"
    raw.write_bytes(bytes(60))
    assert main(["render", str(raw), "-o", str(tmp_path / "x.png")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert (
        len(err) == 1
        and "--raw-shape NX,NY,NZ" in err[0]
        and "--raw-dtype" in err[0]
        and "shape=" not in err[0]
    )
    assert (
        main(["render", str(raw), "--raw-shape", "5,4,3", "-o", str(tmp_path / "x.png"), "--size", "8"]) == 0
    )


def test_headerless_raw_without_a_shape_is_offered_the_cube_its_size_holds(tmp_path, capsys):
    raw = tmp_path / "d.raw"
    raw.write_bytes(bytes(2 * 12**3))
    assert main(["render", str(raw), "-o", str(tmp_path / "x.png")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"volren: error: {raw}: headerless raw data of 3,456 bytes: a 12^3 int16 volume? give --raw-shape "
                   "12,12,12 --raw-dtype int16 (and --raw-spacing, --raw-byte-order as needed)"]  # fmt: skip


def test_convert_takes_the_raw_flags_render_takes(tmp_path, capsys, ml_sample):
    pytest.importorskip("zarr")
    from volren.io import load_volume

    values = np.arange(6 * 5 * 4, dtype=">i2").reshape(6, 5, 4)  # z, y, x
    raw = tmp_path / "d.raw"
    raw.write_bytes(values.tobytes())
    flags = [
        "--raw-shape",
        "4,5,6",
        "--raw-dtype",
        "short",
        "--raw-byte-order",
        "big",
        "--raw-spacing",
        "1,2,3",
    ]
    assert main(["convert", str(raw), str(tmp_path / "d.zarr"), *flags]) == 0
    volume = load_volume(tmp_path / "d.zarr")
    np.testing.assert_array_equal(volume.values, values.astype(np.int16))
    assert volume.spacing == (1.0, 2.0, 3.0)
    capsys.readouterr()
    assert main(["convert", str(raw), str(tmp_path / "e.zarr")]) == 1
    assert "headerless raw data (240 bytes): give --raw-shape NX,NY,NZ" in capsys.readouterr().err
    assert main(["convert", str(ml_sample[0]), str(tmp_path / "f.zarr"), "--raw-dtype", "uchar"]) == 1
    assert "--raw-dtype describes headerless raw data only" in capsys.readouterr().err


def test_timings_print_each_stage_and_the_renderers_own_parts(tmp_path, capsys):
    """Issue 22: `--timings` says where a one-shot render's wall time goes, in one stderr line;
    tetra adds what its frame paid for the mesh and the tables."""
    from benchmarks.oneshot import _stages

    volume, tf = sample_paths("hollow_cylinder")
    assert main(["render", str(volume), "--tf", str(tf), "--renderer", "tetra", "-o", str(tmp_path / "a.png"),
                 "--size", "64x48", "--timings"]) == 0  # fmt: skip
    err = capsys.readouterr().err
    assert len([ln for ln in err.splitlines() if "timings:" in ln]) == 1
    stages = _stages(err)
    assert {"load", "set-up", "frame", "write", "frame: prepare", "frame: tables", "total"} <= set(stages)
    top = sum(v for k, v in stages.items() if ":" not in k and k != "total")
    assert stages["total"] == pytest.approx(top, abs=0.02)
    assert stages["frame: prepare"] + stages["frame: tables"] <= stages["frame"] + 0.01


def test_the_one_shot_benchmark_times_numbas_fixed_cost_in_a_new_interpreter():
    """`benchmarks.oneshot.numba_fixed_seconds`: numba's import, raycast's kernel module and its first
    call, each a real time of a child process that ran the march (not a default when it fails)."""
    import os

    from benchmarks.oneshot import numba_fixed_seconds

    numba_s, module_s, first_call_s = numba_fixed_seconds(dict(os.environ))
    assert 0.0 < numba_s < 60.0 and 0.0 < module_s < 60.0 and 0.0 < first_call_s < 600.0
