"""The example renderer passes the conformance kit, and copies broken on purpose fail the check
that guards what they broke (so the kit, too, is tested)."""

from __future__ import annotations

import numpy as np
import pytest
from volren_example import ExampleRenderer

from volren.model import Camera, TransferFunction1D, UniformVolume
from volren.renderers.base import Capabilities, KindSupport
from volren.testing import conformance_test, run_check, select_checks

# one pytest test per check, as a plugin author's own suite would have it
test_conformance = conformance_test(ExampleRenderer, quick=True)


class StraightAlpha(ExampleRenderer):
    """Colours not multiplied by alpha."""

    def _render(self, camera, width, height, progress):
        image, counters = super()._render(camera, width, height, progress)
        alpha = image[..., 3:4]
        image[..., :3] = np.where(alpha > 0, image[..., :3] / np.maximum(alpha, 1e-12), 0.0).clip(0, 1)
        return image, counters


class Flipped(ExampleRenderer):
    """Row 0 at the bottom."""

    def _render(self, camera, width, height, progress):
        image, counters = super()._render(camera, width, height, progress)
        return np.ascontiguousarray(image[::-1]), counters


class StepIgnored(ExampleRenderer):
    """Each sample takes the TF's opacity as it is, whatever the step (no opacity correction)."""

    def _segment_opacity(self, a, lengths):
        return np.minimum(np.nan_to_num(a), 1.0 - 1e-6)


class CancelSwallowed(ExampleRenderer):
    """Wraps the progress callback so that its exceptions are lost."""

    def _render(self, camera, width, height, progress):
        def quiet(fraction):
            try:
                progress(fraction)
            except Exception:  # noqa: BLE001 - the defect under test
                pass

        return super()._render(camera, width, height, quiet if progress else None)


class ShadingClaimed(ExampleRenderer):
    """Claims shading but ignores it."""

    capabilities = Capabilities(
        kinds={"uniform": KindSupport(blend_modes=ExampleRenderer.capabilities.kinds["uniform"].blend_modes,
                                      shading=True, accuracy=ExampleRenderer.capabilities.kinds["uniform"].accuracy)},
    )  # fmt: skip


class Hangs(ExampleRenderer):
    """Never returns from render (until the test lets it go)."""

    release_event = None

    def _render(self, camera, width, height, progress):
        Hangs.release_event.wait(30)
        return super()._render(camera, width, height, progress)


class Raises(ExampleRenderer):
    def _render(self, camera, width, height, progress):
        raise ZeroDivisionError("the renderer's own bug\nover two lines")


def result_of(renderer_class, check_name, **kwargs):
    (check,) = select_checks([check_name])
    return run_check(check, renderer_class, quick=True, **kwargs)


@pytest.mark.parametrize(
    "broken, check",
    [
        (StraightAlpha, "output"),
        (StraightAlpha, "box"),
        (Flipped, "point"),
        (StepIgnored, "step"),
        (CancelSwallowed, "cancel"),
        (ShadingClaimed, "shading"),
    ],  # fmt: skip
)
def test_a_broken_copy_fails_the_matching_check(broken, check):
    assert result_of(ExampleRenderer, check).passed
    result = result_of(broken, check)
    assert not result.passed
    assert result.failures() and all(line.startswith(f"FAIL {check}") for line in result.failures())


def test_flipped_rows_are_measured_in_pixels():
    result = result_of(Flipped, "point")
    offsets = [m.value for m in result.measurements if m.quantity == "offset px"]
    assert offsets and max(offsets) > 5 * ExampleRenderer.capabilities.kinds["uniform"].accuracy.position_px


def test_a_renderer_that_raises_fails_on_one_line():
    result = result_of(Raises, "box")
    assert not result.passed
    assert result.error == "ZeroDivisionError: the renderer's own bug over two lines"
    assert all("\n" not in line for line in result.lines())


def test_a_renderer_that_hangs_fails_the_check_that_hung():
    import threading

    Hangs.release_event = threading.Event()
    try:
        result = result_of(Hangs, "empty", time_limit=1.0)
    finally:
        Hangs.release_event.set()
    assert not result.passed
    assert "did not finish within 1 s" in result.error


def test_the_example_draws_a_sensible_picture():
    """Not a kit check: a gradient volume renders brighter where the TF is opaque."""
    z, y, x = np.mgrid[0:8, 0:8, 0:8]
    volume = UniformVolume((x + y + z).astype(np.float32))
    tf = TransferFunction1D([[0, 1, 1, 1]], [[0, 0.0], [21, 0.8]])
    renderer = ExampleRenderer()
    renderer.set_volume(volume)
    renderer.set_transfer_function(tf)
    image = renderer.render(Camera.orbit(volume.bounds, 30, 20), 24, 24)
    assert image[..., 3].max() > 0.3 and image[0, 0, 3] == 0
    renderer.release()
