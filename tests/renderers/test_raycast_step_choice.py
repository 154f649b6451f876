"""raycast's target_error option: the largest candidate step whose estimated relative RMSE is
within the target (`volren.renderers.raycast.step_choice`)."""

from __future__ import annotations

import numpy as np
import pytest

from tests.renderers.test_raycast import SHELL_TF, SMOOTH_TF, draw, field
from volren.errors import VolrenError
from volren.model import Camera, RenderSettings
from volren.renderers.raycast import RaycastRenderer
from volren.renderers.raycast import renderer as raycast_module
from volren.renderers.raycast.step_choice import FINE, candidate_steps, largest_step_within, sample_size


@pytest.fixture(autouse=True)
def empty_step_cache(tmp_path, monkeypatch):
    """Every test searches: no step stored on disk by another test (`step_cache`)."""
    monkeypatch.setenv("VOLREN_STEP_CACHE", str(tmp_path / "steps"))


def relative_rmse(image: np.ndarray, fine: np.ndarray) -> float:
    a, b = image.astype(np.float64), fine.astype(np.float64)
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b**2)))


def test_the_sample_is_an_image_of_about_4096_rays_with_the_frames_aspect():
    for width, height in ((512, 512), (800, 600), (8, 8), (1, 300)):
        w, h = sample_size(width, height)
        assert 3500 < w * h < 4700 and abs(w / h - width / height) < 0.05 * width / height + 1.0 / h


def test_the_largest_candidate_within_the_target_is_chosen():
    """With an error growing as h^2, the choice is the largest candidate under the target, and the
    finest when none is."""
    fine = np.full((10, 4), 0.5)

    def march(h: float) -> np.ndarray:
        return fine + 0.1 * h**2

    steps = candidate_steps(1.0)
    error = {h: 0.1 * (h**2 - FINE**-2) / (0.5 + 0.1 * FINE**-2) for h in steps}  # over the fine rays' RMS
    for target in (0.5, 0.1, 0.03):
        h, estimate = largest_step_within(march, 1.0, target)
        assert h == max(s for s in steps if error[s] <= target)
        assert estimate == pytest.approx(error[h])
    assert largest_step_within(march, 1.0, 1e-6)[0] == steps[-1]


@pytest.mark.parametrize("pre", [False, True])
def test_the_chosen_step_is_the_largest_candidate_within_the_target(pre):
    """Drawn at the sample's own size (64x64), the estimate is exact: the frame at the chosen step
    is within the target of the march 16x finer, the next coarser candidate is not, and the frame
    is the one drawn with that step given directly."""
    volume = field()
    camera = Camera.orbit(volume.bounds, 30, 20, zoom=1.2)
    target = 0.005  # the shell TF's error: 0.6 % at step 0.6, 0.46 % at 0.5 (post-classified)
    size = sample_size(64, 64)
    assert size == (64, 64)
    image, renderer = draw(volume, SHELL_TF, camera, size, step=1.0, preintegration=pre,
                           options={"target_error": target})  # fmt: skip
    counters = renderer.last_frame.counters
    chosen = counters["step"]
    fine, _ = draw(volume, SHELL_TF, camera, size, step=1.0 / FINE, preintegration=pre)
    assert relative_rmse(image, fine) <= target
    assert relative_rmse(image, fine) == pytest.approx(counters["step_relative_error"], rel=1e-3)
    steps = candidate_steps(1.0)
    k = int(np.argmin([abs(s - chosen) for s in steps]))
    assert 0 < k < len(steps) - 1  # the field needs a finer step than 1 and a coarser one than the finest
    coarser, _ = draw(volume, SHELL_TF, camera, size, step=steps[k - 1], preintegration=pre)
    assert relative_rmse(coarser, fine) > target
    direct, _ = draw(volume, SHELL_TF, camera, size, step=chosen, preintegration=pre)
    np.testing.assert_allclose(image, direct, atol=1e-6)


def test_the_choice_does_not_depend_on_the_first_frames_size():
    """The app warms a renderer up with an 8x8 frame: the step it keeps is the one a 512x512 first
    frame would choose."""
    volume = field()
    camera = Camera.orbit(volume.bounds, 30, 20, zoom=1.2)
    options = {"target_error": 0.005}
    _, small = draw(volume, SHELL_TF, camera, (8, 8), step=1.0, options=options)
    _, large = draw(volume, SHELL_TF, camera, (512, 512), step=1.0, options=options)
    assert small.last_frame.counters["step"] == large.last_frame.counters["step"] < 1.0


def test_the_step_is_kept_while_the_camera_turns_and_chosen_again_for_a_new_tf(monkeypatch):
    calls = []
    real = raycast_module.largest_step_within
    monkeypatch.setattr(raycast_module, "largest_step_within", lambda *a: calls.append(a) or real(*a))
    volume = field()
    tf = SMOOTH_TF.copy()
    renderer = RaycastRenderer()
    renderer.set_volume(volume)
    renderer.set_transfer_function(tf)
    renderer.set_settings(RenderSettings(step=1.0, options={"target_error": 0.01}))
    for azimuth in (30, 40, 50):
        renderer.render(Camera.orbit(volume.bounds, azimuth, 20), 40, 32)
        if azimuth > 30:
            assert renderer.last_frame.counters["step_choice_ms"] < 1.0  # kept: nothing estimated
    assert len(calls) == 1
    tf.set_color_points([[-2, 1.0, 0.3, 0.3], [4, 0.1, 0.8, 0.1]])  # colour only: the error changes too
    renderer.render(Camera.orbit(volume.bounds, 50, 20), 40, 32)
    assert len(calls) == 2


@pytest.mark.parametrize("value", [-0.1, 1.5, True, "0.01"])
def test_a_bad_target_is_a_one_line_error(value):
    with pytest.raises(VolrenError, match="target_error") as err:
        RaycastRenderer().set_settings(RenderSettings(options={"target_error": value}))
    assert "\n" not in str(err.value)
