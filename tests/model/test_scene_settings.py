"""RenderSettings and Scene: validation and versioned JSON round trips."""

from __future__ import annotations

import numpy as np
import pytest

from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.scene import OrbitView, Scene
from volren.model.settings import BlendMode, RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import UniformVolume


def test_settings_round_trip_and_aliases():
    settings = RenderSettings(step=0.25, shade=True, blend_mode="mip", options={"mapper": "gpu"})
    assert settings.blend_mode is BlendMode.MAXIMUM
    assert RenderSettings.from_dict(settings.to_dict()) == settings


@pytest.mark.parametrize(
    "changes, message",
    [
        ({"step": 0}, "positive"),
        ({"step": float("inf")}, "finite"),
        ({"ambient": -1}, ">= 0"),
        ({"shade": "yes"}, "true or false"),
        ({"blend_mode": "xray"}, "composite, maximum"),
        ({"stpe": 1}, "unknown render settings"),
    ],
)
def test_bad_settings(changes, message):
    with pytest.raises(VolrenError, match=message):
        RenderSettings().with_(**changes)


def test_scene_round_trip_with_orbit_and_explicit_camera():
    tf = TransferFunction1D.ramp(0, 10, 0.5)
    scene = Scene(
        "data/head.mhd",
        tf,
        OrbitView(30, 20, 1.5, True),
        RenderSettings(step=0.3),
        "v",
        "reference",
        (64, 32),
    )
    again = Scene.from_dict(scene.to_dict())
    assert again.camera == scene.camera and again.settings == scene.settings
    assert (again.volume_path, again.scalars, again.renderer, again.size) == (
        "data/head.mhd",
        "v",
        "reference",
        (64, 32),
    )
    camera = Camera.orbit((0, 1, 0, 1, 0, 1), 10, 10, 1)
    explicit = Scene.from_dict(Scene("x.vti", tf, camera).to_dict())
    assert explicit.camera == camera and explicit.resolved_camera() == camera


def test_orbit_camera_needs_bounds_from_the_volume():
    tf = TransferFunction1D.ramp(0, 1)
    scene = Scene("x.vti", tf, OrbitView(30, 20), size=(100, 50))
    with pytest.raises(VolrenError, match="no volume"):
        scene.resolved_camera()
    volume = UniformVolume(np.zeros((4, 4, 4), np.float32))
    camera = scene.with_volume(volume).resolved_camera()
    assert camera == Camera.orbit(volume.bounds, 30, 20, 1.0, False, 2.0)


@pytest.mark.parametrize(
    "patch, message",
    [
        ({"version": 99}, "newer"),
        ({"version": None}, "integer"),
        ({"transfer_function": None}, "JSON object"),
        ({"camera": {"azimuth": "a"}}, "finite number"),
        ({"camera": {"yaw": 3}}, "unknown camera keys"),
        ({"size": [0, 3]}, "positive integers"),
        ({"settings": {"step": -1}}, "positive"),
    ],
)
def test_bad_scene_json(patch, message):
    data = Scene("x.vti", TransferFunction1D.ramp(0, 1)).to_dict()
    data.update(patch)
    with pytest.raises(VolrenError, match=message):
        Scene.from_dict(data)
