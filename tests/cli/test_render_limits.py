"""Absurd `volren render` flags are one-line errors naming the flag, never a blank image and exit 0,
and a transfer function that shows nothing of the data is a one-line warning (issue 25)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import volren
from volren.cli.main import main
from volren.errors import VolrenError, VolrenWarning
from volren.model.settings import MAX_SAMPLES_PER_RAY, MAX_STEP, RenderSettings, check_step, samples_per_ray
from volren.model.tf_coverage import coverage_problem
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TFWidget, TransferFunction2D
from volren.model.volume import UniformVolume
from volren.samples import sample_paths


@pytest.fixture(scope="module")
def ml_volume():
    return str(sample_paths("marschner_lobb")[0])


def _render(tmp_path, volume, *flags: str) -> list[str]:
    return ["render", volume, "-o", str(tmp_path / "x.png"), "--size", "8", *flags]


@pytest.mark.parametrize(
    "flags",
    [
        ["--step", "0"],
        ["--step", "-1"],
        ["--step", "nan"],
        ["--step", "inf"],
        ["--step", "1e300"],
        ["--size", "0"],
        ["--size", "100000"],
        ["--size", "10x0"],
        ["--size", "-5"],
        ["--zoom", "0"],
        ["--zoom", "-1"],
        ["--zoom", "nan"],
        ["--azimuth", "nan"],
        ["--elevation", "inf"],
        ["--elevation", "-inf"],
    ],
)
def test_out_of_domain_values_are_usage_errors_naming_the_flag(tmp_path, capsys, ml_volume, flags):
    with pytest.raises(SystemExit) as exc:
        main(_render(tmp_path, ml_volume, *flags))
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("volren render: error: argument " + flags[0]), err
    assert not (tmp_path / "x.png").exists()


@pytest.mark.parametrize(
    "flags, names",
    [
        (["--step", "1e-9"], ["--step 1e-09", f"{MAX_SAMPLES_PER_RAY:,}", "at least 0.000693"]),
        (["--step", "1e-300"], ["--step 1e-300", f"{MAX_SAMPLES_PER_RAY:,}"]),
        (["--zoom", "0.1"], ["--zoom 0.1", "perspective", "0.1667"]),
        (["--zoom", "1e300"], ["--zoom", "1e+06"]),
        (["--zoom", "1e-300", "--parallel"], ["--zoom", "1e-06"]),
    ],
)
def test_absurd_values_are_one_line_errors_naming_the_flag_and_limit(
    tmp_path, capsys, ml_volume, flags, names
):
    assert main(_render(tmp_path, ml_volume, *flags)) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("volren: error: "), err
    assert all(n in err[0] for n in names), err
    assert not (tmp_path / "x.png").exists()


def test_a_scene_step_too_small_names_the_scene(tmp_path, capsys, ml_volume):
    scene = {
        "version": 1,
        "volume": {"path": ml_volume},
        "settings": {"step": 1e-9},
        "transfer_function": TransferFunction1D.ramp(0, 1).to_dict(),
    }
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene))
    assert main(["render", "--scene", str(path), "-o", str(tmp_path / "x.png")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"{path}: settings.step (or --step) 1e-09" in err[0], err


def test_the_step_limit_follows_the_diagonal_in_units_of_the_step():
    bounds = (0, 40, 0, 40, 0, 40)  # marschner_lobb: 41^3 voxels of spacing 1
    assert samples_per_ray(1.0, bounds, 1.0) == pytest.approx(40 * 3**0.5)
    least = 40 * 3**0.5 / MAX_SAMPLES_PER_RAY
    check_step(least * 1.001, bounds, 1.0)
    with pytest.raises(VolrenError, match=r"render setting step .* at least 0\.000693"):
        check_step(least * 0.999, bounds, 1.0)


def test_the_api_refuses_the_same_steps():
    volume = UniformVolume(np.linspace(0, 1, 64, dtype=np.float32).reshape(4, 4, 4))
    with pytest.raises(VolrenError, match="render setting step 1e-09 would take"):
        volren.render(volume, renderer="reference", size=4, step=1e-9)


@pytest.mark.slow  # about 20 s
@pytest.mark.usefixtures("opengl")
def test_a_small_legal_step_is_honoured(tmp_path, ml_volume):
    """Step 0.001 is 69,000 samples per ray here: legal, and drawn (VTK went blank near 690,000)."""
    images = []
    for step in ("0.5", "0.001"):
        out = tmp_path / f"{step}.npy"
        assert main(["render", ml_volume, "--save-array", str(out), "--size", "12", "--step", step]) == 0
        images.append(np.load(out))
    assert images[1][..., 3].mean() > 0.1
    assert np.abs(images[0] - images[1]).max() < 0.05


# ------------------------------------------------------------------ TFs that show nothing
def _ramp(lo: float, hi: float, floor: float = 0.0) -> TransferFunction1D:
    return TransferFunction1D([[lo, 1, 1, 1], [hi, 1, 0, 0]], [[lo, floor], [hi, 1.0]])


@pytest.mark.parametrize(
    "tf, words",
    [
        (_ramp(1000, 2000), ["opacity is 0", "[1000, 2000]", "[0, 1]"]),
        (TransferFunction1D([[0, 1, 1, 1]], [[-5, 0], [0.5, 0], [0.7, 0], [9, 0]]), ["opacity is 0"]),
        # a step down at the range's bottom: its other side holds values below the data's
        (TransferFunction1D([[0, 1, 1, 1]], [[-1, 0.3], [0, 0.3], [0, 0], [1, 0]]), ["opacity is 0"]),
        (_ramp(1000, 2000, floor=0.5), ["misses", "[1000, 2000]", "[0, 1]"]),
        (_ramp(-3, -1, floor=0.2), ["misses"]),
        (TransferFunction2D((0, 1), (0, 1), []), ["no widget"]),
        (TransferFunction2D((5, 9), (0, 1), [TFWidget.box((5, 9), (0, 1), (1, 1, 1), 0.5)]), ["misses"]),
    ],
)
def test_coverage_problems_name_both_ranges(tf, words):
    problem = coverage_problem(tf, (0.0, 1.0))
    assert problem is not None and all(w in problem for w in words), problem


@pytest.mark.parametrize(
    "tf",
    [
        _ramp(0, 1),
        _ramp(-10, 0.5),  # visible over half the data
        TransferFunction1D([[0, 1, 1, 1]], [[0.2, 0], [0.3, 0.4], [0.4, 0]]),  # a peak inside only
        # a ramp that drops to 0 at once (a step: two points at 0.75), as oxygen's default TF: it was
        # called black because the TF sampled at the step gives the side after it
        TransferFunction1D([[0, 1, 1, 1]], [[0, 0], [0.07, 0], [0.75, 0.2], [0.75, 0], [1, 0]]),
        TransferFunction1D([[0, 1, 1, 1]], [[0, 0], [1, 0.2], [1, 0]]),  # the step at the range's top
        TransferFunction1D.constant(0.3),  # one control point: constant on purpose
        TransferFunction1D([[5, 1, 1, 1]], [[5, 0.3]]),
    ],
)
def test_tfs_that_show_the_data_pass(tf):
    assert coverage_problem(tf, (0.0, 1.0)) is None


@pytest.mark.filterwarnings("default::volren.errors.VolrenWarning")
def test_render_warns_once_naming_the_tf_file_and_both_ranges(tmp_path, capsys, ml_volume):
    tf = tmp_path / "other.tf.json"
    tf.write_text(json.dumps(_ramp(1000, 2000).to_dict()))
    code = main(_render(tmp_path, ml_volume, "--tf", str(tf), "--renderer", "reference"))
    captured = capsys.readouterr()
    assert code == 0 and captured.out.startswith("reference: 8x8 in ")
    err = captured.err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"volren: warning: {tf}: the opacity is 0"), err
    assert "[1000, 2000]" in err[0] and "the data [" in err[0]


def test_the_api_warns_alike():
    volume = UniformVolume(np.linspace(0, 1, 64, dtype=np.float32).reshape(4, 4, 4))
    with pytest.warns(VolrenWarning, match=r"transfer function: the opacity is 0 .*\[1000, 2000\]"):
        volren.render(volume, _ramp(1000, 2000), renderer="reference", size=4)


def test_settings_still_refuse_non_positive_steps():
    with pytest.raises(VolrenError, match="step must be finite and positive"):
        RenderSettings(step=0.0)


def test_settings_refuse_steps_past_the_longest():
    RenderSettings(step=MAX_STEP)
    with pytest.raises(
        VolrenError, match=r"^render setting step must be at most 1000 \(in voxel lengths\), got 1e\+300$"
    ):
        RenderSettings(step=1e300)


def test_an_empty_renderer_name_is_refused_naming_the_flag(tmp_path, capsys, ml_volume):
    assert main(_render(tmp_path, ml_volume, "--renderer", "")) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        "volren: error: --renderer: give a renderer name (see `volren renderers`), got an empty one"
    ]
    assert not (tmp_path / "x.png").exists()
