"""A constant volume of a large value: a table over its value range must still have a width
(lo + 1 == lo from about 1e16 on, and the division by zero ended the render)."""

from __future__ import annotations

import numpy as np
import pytest

from volren.model import Camera, TransferFunction1D, UniformVolume
from volren.model.volume import spanning
from volren.renderers.base import render_frame
from volren.renderers.registry import registry


@pytest.mark.parametrize("lo", [0.0, 1.0, -7.5, 1e300, -1e300, 3.0e38, 1.7e308])
def test_a_constant_range_gets_a_width_a_division_can_use(lo):
    a, b = spanning(lo, lo)
    assert a == lo and b > a and np.isfinite(b) and np.isfinite(1.0 / (b - a))
    assert spanning(lo, lo + abs(lo) + 1.0) == (lo, lo + abs(lo) + 1.0)  # a range with a width stays


@pytest.mark.parametrize("renderer", ["raycast", "shearwarp", "objectorder"])
@pytest.mark.parametrize("value", [1e30, -3e38])
def test_cpu_renderers_draw_a_constant_volume_of_a_large_value(renderer, value):
    volume = UniformVolume(np.full((6, 6, 6), value, dtype=np.float32))
    tf = TransferFunction1D([[value, 1.0, 0.5, 0.2]], [[value, 0.4]])  # one point: constant by design
    with registry.create(renderer) as r:
        r.set_volume(volume)
        r.set_transfer_function(tf)
        image, _ = render_frame(r, Camera.orbit(volume.bounds), 16, 16)
    assert np.all(np.isfinite(image)) and image[..., 3].max() > 0.1  # the cube is drawn, not blank
