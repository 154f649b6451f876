"""raycast with 2D transfer functions (`march2d`), against exact oracles.

(a) a 2D TF made from a 1D one (`seeded_2d`) draws what the 1D TF draws, the 1D march being the
oracle (the same samples; the 2D table is bilinear where the 1D one is linear); (b) on a linear
ramp |grad s| is one constant G, so a band whose gradient interval excludes G draws nothing and one
including it draws the 1D image; (c) skipping empty bricks and clipping change nothing they must
not: the image without skipping, and the 1D march's clipped image, are the oracles.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from volren.app.core.tf_seeding import seeded_2d
from volren.model import Camera, TFWidget, TransferFunction1D, TransferFunction2D, UniformVolume
from volren.model.clip_region import ClipPlane, ClipRegion
from volren.model.colormaps import VIRIDIS, color_stops
from volren.model.settings import RenderSettings
from volren.renderers.raycast import RaycastRenderer
from volren.renderers.raycast import renderer as raycast_module
from volren.renderers.raycast.step_choice import FINE, candidate_steps, sample_size
from volren.testing.render_helpers import render_checked

STEP = 0.3  # a fixed step: the 1D march's error-targeted search is off (target_error 0)
FIXED = {"target_error": 0.0}


def _ramp_tf(lo: float, hi: float) -> TransferFunction1D:
    return TransferFunction1D(
        np.array(color_stops(VIRIDIS, lo, hi)),
        np.array([[lo, 0.0], [lo + 0.3 * (hi - lo), 0.05], [lo + 0.7 * (hi - lo), 0.4], [hi, 0.1]]),
        opacity_unit_distance=2.0,
    )


def _blob() -> UniformVolume:
    z, y, x = np.mgrid[0:20, 0:18, 0:22].astype(np.float64)
    r = np.sqrt((x - 10.5) ** 2 + (y - 8.0) ** 2 + (z - 9.5) ** 2)
    return UniformVolume(np.exp(-((r / 6.0) ** 2)), spacing=(1.0, 0.9, 1.2))


def _draw(volume, tf, camera, **settings):
    options = {**FIXED, **settings.pop("options", {})}
    image, renderer = render_checked(RaycastRenderer, volume, tf, camera, (48, 40), step=STEP,
                                     options=options, **settings)  # fmt: skip
    return image, renderer


@pytest.fixture(scope="module")
def blob():
    volume = _blob()
    return volume, Camera.orbit(volume.bounds, 30.0, 20.0, 1.2)


def _gradient_max(volume: UniformVolume) -> float:
    parts = np.gradient(np.asarray(volume.values, np.float64), *volume.spacing[::-1])
    return float(np.sqrt(sum(p**2 for p in parts)).max())


def test_a_2d_tf_made_from_a_1d_one_draws_the_1d_image(blob):
    volume, camera = blob
    tf1 = _ramp_tf(*volume.value_range)
    tf2 = seeded_2d(tf1, volume.value_range, _gradient_max(volume))
    one, _ = _draw(volume, tf1, camera)
    two, renderer = _draw(volume, tf2, camera)
    assert one[..., 3].max() > 0.3  # something to compare
    # the 2D table holds 512 entries along value where the 1D march reads the TF's own segments
    np.testing.assert_allclose(two, one, atol=2e-3)
    assert renderer.last_frame.counters["samples"] > 0


def _ramp() -> UniformVolume:
    z, y, x = np.mgrid[0:12, 0:10, 0:14].astype(np.float64)
    return UniformVolume(0.05 * x + 0.03 * y + 0.02 * z, spacing=(1.0, 1.0, 1.0))


@pytest.mark.parametrize("inside", [True, False])
def test_on_a_ramp_only_a_band_holding_its_one_gradient_draws(inside):
    volume = _ramp()
    g = math.sqrt(0.05**2 + 0.03**2 + 0.02**2)  # central and one-sided differences are exact on a ramp
    lo, hi = volume.value_range
    tf1 = _ramp_tf(lo, hi)
    band = (0.5 * g, 1.5 * g) if inside else (1.5 * g, 3.0 * g)
    widget = TFWidget.from_1d(tf1, band)
    tf2 = TransferFunction2D((lo, hi), (0.0, 3.0 * g), [widget], tf1.opacity_unit_distance)
    camera = Camera.orbit(volume.bounds, 20.0, 15.0, 1.1)
    two, _ = _draw(volume, tf2, camera)
    if inside:
        one, _ = _draw(volume, tf1, camera)
        assert one[..., 3].max() > 0.1
        np.testing.assert_allclose(two, one, atol=2e-3)
    else:
        assert two.max() == 0.0


def test_skipping_empty_bricks_leaves_the_image_as_it_is(blob):
    volume, camera = blob
    lo, hi = volume.value_range
    gmax = _gradient_max(volume)
    # visible only at high values and steep gradients: most bricks are empty
    tf2 = TransferFunction2D(
        (lo, hi), (0.0, gmax), [TFWidget.box((0.6, 1.0), (0.3 * gmax, gmax), (0.9, 0.4, 0.1), 0.5)]
    )
    skipped, renderer = _draw(volume, tf2, camera)
    whole, _ = _draw(volume, tf2, camera, options={"empty_space_skipping": False})
    assert skipped[..., 3].max() > 0.05
    assert renderer.last_frame.counters["bricks_empty"] > 0
    np.testing.assert_array_equal(skipped, whole)


def test_a_clipped_2d_frame_is_the_clipped_1d_frame(blob):
    volume, camera = blob
    tf1 = _ramp_tf(*volume.value_range)
    tf2 = seeded_2d(tf1, volume.value_range, _gradient_max(volume))
    lo, hi = np.asarray(volume.bounds[0::2]), np.asarray(volume.bounds[1::2])
    clip = ClipRegion((ClipPlane(tuple((lo + hi) / 2), (1.0, 0.4, -0.3)),))
    one, _ = _draw(volume, tf1, camera, clip=clip)
    two, _ = _draw(volume, tf2, camera, clip=clip)
    uncut, _ = _draw(volume, tf1, camera)
    assert np.abs(one - uncut).max() > 0.05  # the plane cuts something visible
    np.testing.assert_allclose(two, one, atol=2e-3)


def _gaussian_tf(volume: UniformVolume, center: float, width: float = 0.15) -> TransferFunction2D:
    """A Gaussian widget at value fraction `center`, half way up the gradient axis: its opacity is
    nowhere 0, and its samples read the gradient."""
    lo, hi = volume.value_range
    gmax = _gradient_max(volume)
    widget = TFWidget.gaussian(
        (lo + center * (hi - lo), 0.5 * gmax), (width * (hi - lo), 0.3 * gmax), (0.9, 0.5, 0.2), 0.6
    )
    return TransferFunction2D((lo, hi), (0.0, gmax), [widget], 2.0)


def _relative_rmse(image: np.ndarray, fine: np.ndarray) -> float:
    a, b = image.astype(np.float64), fine.astype(np.float64)
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b**2)))


def test_an_error_target_chooses_the_largest_step_within_it_for_a_2d_tf(blob, tmp_path, monkeypatch):
    """As for 1D TFs: drawn at the search's own size (64x64) the estimate is exact, so the frame is
    within the target of the march 16x finer, the next coarser candidate is not, and the frame is
    the one drawn at that step given directly."""
    monkeypatch.setenv("VOLREN_STEP_CACHE", str(tmp_path))
    volume, camera = blob
    tf2 = _gaussian_tf(volume, 0.5, 0.04)  # a thin shell: step 2 misses it
    target, size = 0.004, sample_size(64, 64)
    image, renderer = render_checked(RaycastRenderer, volume, tf2, camera, size, step=2.0,
                                     options={"target_error": target})  # fmt: skip
    counters = renderer.last_frame.counters
    chosen = counters["step"]

    def at(step: float) -> np.ndarray:
        return render_checked(RaycastRenderer, volume, tf2, camera, size, step=step, options=FIXED)[0]

    fine = at(2.0 / FINE)
    assert _relative_rmse(image, fine) <= target
    assert _relative_rmse(image, fine) == pytest.approx(counters["step_relative_error"], rel=1e-3)
    steps = candidate_steps(2.0)
    k = int(np.argmin([abs(s - chosen) for s in steps]))
    assert 0 < k < len(steps) - 1  # the blob needs a finer step than 2 and a coarser one than the finest
    assert _relative_rmse(at(steps[k - 1]), fine) > target
    np.testing.assert_array_equal(image, at(chosen))


def test_the_2d_step_is_kept_while_the_camera_turns_and_searched_again_after_an_edit(
    blob, tmp_path, monkeypatch
):
    monkeypatch.setenv("VOLREN_STEP_CACHE", str(tmp_path))
    calls = []
    real = raycast_module.largest_step_within
    monkeypatch.setattr(raycast_module, "largest_step_within", lambda *a: calls.append(a) or real(*a))
    volume, _ = blob
    tf2 = _gaussian_tf(volume, 0.5)
    renderer = RaycastRenderer()
    renderer.set_volume(volume)
    renderer.set_transfer_function(tf2)
    renderer.set_settings(RenderSettings(step=2.0, options={"target_error": 0.004}))
    for azimuth in (30, 40):
        renderer.render(Camera.orbit(volume.bounds, azimuth, 20), 40, 32)
    assert len(calls) == 1
    tf2.replace_widget(0, _gaussian_tf(volume, 0.4).widgets[0])
    renderer.render(Camera.orbit(volume.bounds, 40, 20), 40, 32)
    assert len(calls) == 2


def test_a_gaussians_faint_tails_leave_bricks_empty_within_the_negligible_opacity(blob, monkeypatch):
    """A Gaussian over the top values is faintly non-zero at every value: with the table's floor
    the bricks below it are skipped, and the image differs from the exact table's by at most
    `NEGLIGIBLE_OPACITY` (the most a ray can lose, whatever the dropped entries)."""
    volume, camera = blob
    tf2 = _gaussian_tf(volume, 0.95)
    floored, renderer = _draw(volume, tf2, camera)
    negligible = raycast_module.NEGLIGIBLE_OPACITY
    monkeypatch.setattr(raycast_module, "NEGLIGIBLE_OPACITY", 0.0)
    exact, exact_renderer = _draw(volume, tf2, camera)
    assert floored[..., 3].max() > 0.05  # the widget draws something
    assert exact_renderer.last_frame.counters["bricks_empty"] == 0  # no entry of the exact table is 0
    assert renderer.last_frame.counters["bricks_empty"] > 0
    assert renderer.last_frame.counters["samples"] < exact_renderer.last_frame.counters["samples"]
    difference = np.abs(floored.astype(np.float64) - exact).max()
    assert 0.0 < difference <= negligible


def test_a_drags_smaller_table_is_sampled_at_its_size_and_draws_close_to_the_full_one(blob):
    """`table_2d` sets the entries along value (half as many along gradient magnitude); the drag's
    128 draws a smooth Gaussian within a few thousandths of the slicer's 512."""
    volume, camera = blob
    tf2 = _gaussian_tf(volume, 0.5)
    full, full_renderer = _draw(volume, tf2, camera)
    small, small_renderer = _draw(volume, tf2, camera, options={"table_2d": 128})
    assert full_renderer._table2d[1].shape == (256, 512, 4)
    assert small_renderer._table2d[1].shape == (64, 128, 4)
    assert full[..., 3].max() > 0.1
    assert 0.0 < np.abs(small - full).max() < 5e-3
