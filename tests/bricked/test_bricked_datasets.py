"""Issue 24's goal on real data: bonsai and engine cut into 64^3 and 100^3 bricks render with the
slicer, composited sort-last, within RMSE 1e-5 of the whole-volume render, in parallel and
perspective views (early termination off: a brick's layer cannot know the opacity in front)."""

from __future__ import annotations

import numpy as np
import pytest

from tests.conftest import load_scene_tf
from volren.api import prepared_renderer
from volren.bricked.sort_last import render_bricked
from volren.bricked.source import VolumeSource
from volren.io.volume_io import load_volume
from volren.model.camera import Camera
from volren.model.settings import RenderSettings

CASES = [
    ("bonsai", 64, RenderSettings(options={"early_termination": False})),
    ("bonsai", 100, RenderSettings(preintegration=True, shade=True, options={"early_termination": False})),
    ("engine", 64, RenderSettings(preintegration=True, options={"early_termination": False})),
    ("engine", 100, RenderSettings(shade=True, options={"early_termination": False})),
]


@pytest.mark.slow  # 4-6 s per bonsai case
@pytest.mark.usefixtures("opengl")
@pytest.mark.parametrize("parallel", [False, True], ids=["perspective", "parallel"])
@pytest.mark.parametrize("name, brick, settings", CASES, ids=[f"{c[0]}-{c[1]}" for c in CASES])
def test_bricked_equals_whole_on_real_data(shared_data, name, brick, settings, parallel):
    volume = load_volume(shared_data / "uniform" / f"{name}.vti")
    tf = load_scene_tf(f"{name}-smooth")
    camera = Camera.orbit(volume.bounds, 30, 20, parallel=parallel)
    with prepared_renderer("slicer", volume, tf, settings) as renderer:
        whole = renderer.render(camera, 96, 96)
        bricked, stats = render_bricked(renderer, VolumeSource(volume), tf, camera, 96, 96, brick=brick)
    assert stats.drawn >= 8
    assert whole[..., 3].mean() > 0.05
    error = float(np.sqrt(np.mean((bricked.astype(np.float64) - whole) ** 2)))
    print(
        f"{name} {brick}^3 {'parallel' if parallel else 'perspective'}: RMSE {error:.3g}, {stats.drawn} bricks"
    )
    assert error <= 1e-5
