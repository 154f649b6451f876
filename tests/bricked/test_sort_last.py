"""A bricked frame equals the whole frame (reference and slicer, on small volumes), bricks the TF
makes transparent are never read, and what cannot be bricked is a one-line error."""

from __future__ import annotations

import numpy as np
import pytest

from volren.api import prepared_renderer
from volren.bricked.layout import BrickLayout
from volren.bricked.sort_last import render_bricked
from volren.bricked.source import VolumeSource
from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.region import Region
from volren.model.settings import BlendMode, RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import UniformVolume
from volren.renderers.registry import registry


def field_volume(shape=(14, 11, 9), spacing=(1.1, 0.9, 1.0)) -> UniformVolume:
    z, y, x = np.meshgrid(*(np.arange(n, dtype=np.float64) for n in shape), indexing="ij")
    values = np.sin(0.5 * x) + np.cos(0.4 * y) + 0.2 * z
    return UniformVolume(values.astype(np.float32), spacing, (-3.0, 1.0, 0.5))


TF = TransferFunction1D(
    [[-2, 0.1, 0.4, 1.0], [0.5, 0.9, 0.9, 0.2], [5, 1.0, 0.2, 0.1]],
    [[-2, 0.0], [0.0, 0.05], [1.0, 0.5], [5, 0.2]],
    1.5,
)


class CountingSource(VolumeSource):
    """Remembers every block read."""

    def __init__(self, volume):
        super().__init__(volume)
        self.reads: list[tuple[slice, ...]] = []

    def read(self, slices):
        self.reads.append(slices)
        return super().read(slices)


def whole_and_bricked(name, volume, tf, camera, settings, brick, size=(20, 16)):
    with prepared_renderer(name, volume, tf, settings) as renderer:
        whole = renderer.render(camera, *size)
        bricked, stats = render_bricked(renderer, VolumeSource(volume), tf, camera, *size, brick=brick)
        assert renderer.region is None  # cleared after the frame
        renderer.set_volume(volume)
        again = renderer.render(camera, *size)  # and whole volumes draw as before
    return whole, bricked, again, stats


def rmse(a, b):
    return float(np.sqrt(np.mean((a.astype(np.float64) - b) ** 2)))


CAMERAS = {
    "perspective": lambda v: Camera.orbit(v.bounds, 35, 25, zoom=1.2),
    "parallel": lambda v: Camera.orbit(v.bounds, -60, -10, parallel=True),
}


@pytest.mark.parametrize("camera", CAMERAS)
@pytest.mark.parametrize("shade", [False, True])
def test_reference_bricked_equals_whole(camera, shade):
    volume = field_volume()
    settings = RenderSettings(shade=shade, options={"tolerance": 1e-6})
    whole, bricked, _, stats = whole_and_bricked(
        "reference", volume, TF, CAMERAS[camera](volume), settings, 4
    )
    assert stats.drawn > 8 and stats.ghost == 1
    assert np.abs(whole).max() > 0.05
    assert rmse(bricked, whole) <= 1e-6


@pytest.mark.usefixtures("opengl")
@pytest.mark.parametrize("camera", CAMERAS)
@pytest.mark.parametrize("pre, shade", [(False, False), (True, False), (True, True), (False, True)])
def test_slicer_bricked_equals_whole(camera, pre, shade):
    volume = field_volume()
    settings = RenderSettings(preintegration=pre, shade=shade, options={"early_termination": False})
    whole, bricked, again, stats = whole_and_bricked(
        "slicer", volume, TF, CAMERAS[camera](volume), settings, 4
    )
    assert stats.drawn > 8 and stats.ghost == (2 if pre else 1)
    assert np.abs(whole).max() > 0.05
    assert rmse(bricked, whole) <= 1e-5
    assert np.array_equal(again, whole)


@pytest.mark.usefixtures("opengl")
def test_slicer_steps_longer_than_a_voxel_ask_for_more_ghost_voxels():
    volume = field_volume()
    settings = RenderSettings(preintegration=True, step=2.5, options={"early_termination": False})
    camera = CAMERAS["perspective"](volume)
    whole, bricked, _, stats = whole_and_bricked("slicer", volume, TF, camera, settings, 3)
    assert stats.ghost >= 4
    assert rmse(bricked, whole) <= 1e-5


def test_bricks_the_tf_makes_transparent_are_never_read():
    values = np.zeros((20, 20, 20), dtype=np.float32)
    values[14:, 14:, 14:] = 10.0  # only the far corner holds anything the TF shows
    volume = UniformVolume(values)
    tf = TransferFunction1D([[0, 1, 1, 1], [10, 1, 0, 0]], [[0, 0.0], [5, 0.0], [10, 0.6]])
    source = CountingSource(volume)
    renderer = registry.create("reference")
    try:
        camera = Camera.orbit(volume.bounds, 20, 20)
        image, stats = render_bricked(renderer, source, tf, camera, 16, 16, brick=4)
        renderer.set_volume(volume)
        whole = renderer.render(camera, 16, 16)
    finally:
        renderer.release()
    assert stats.bricks == 125 and stats.transparent == stats.bricks - stats.drawn
    assert stats.drawn == len(source.reads) <= 27  # the corner's bricks and their neighbours
    for z, y, x in source.reads:
        assert min(z.stop, y.stop, x.stop) >= 14  # every block read reaches the corner
    assert image.max() > 0.1 and rmse(image, whole) <= 1e-6


def test_what_cannot_be_bricked_is_a_one_line_error():
    volume = field_volume()
    camera = Camera.orbit(volume.bounds)
    layout = BrickLayout(volume.dimensions, volume.spacing, volume.origin, volume.value_range, 4)
    region = layout.region(layout.brick_at((1, 1, 1)))
    renderer = registry.create("reference")
    try:
        renderer.set_transfer_function(TF)
        renderer.set_volume(volume)
        renderer.set_settings(RenderSettings(blend_mode=BlendMode.MAXIMUM))
        renderer.set_region(region)
        with pytest.raises(VolrenError, match="composite blend mode"):
            renderer.render(camera, 8, 8)
        renderer.set_settings(RenderSettings())
        small = UniformVolume(volume.values[:3, :3, :3], volume.spacing, volume.origin)
        renderer.set_volume(small)
        renderer.set_region(region)
        with pytest.raises(VolrenError, match="not inside the sub-volume"):
            renderer.render(camera, 8, 8)
        with pytest.raises(VolrenError, match="needs a Region"):
            renderer.set_region((0, 0, 0))
    finally:
        renderer.release()
    shearwarp = registry.create("shearwarp")
    try:
        with pytest.raises(VolrenError, match="does not draw bricks"):
            shearwarp.set_region(region)
        shearwarp.set_settings(RenderSettings())
        with pytest.raises(VolrenError, match="does not draw bricks"):
            render_bricked(shearwarp, VolumeSource(volume), TF, camera, 8, 8)
    finally:
        shearwarp.release()
    assert Region((0, 0, 0), (1, 1, 1), (0, 1, 0, 1, 0, 1), (0, 1)).owns(
        np.array([[1.0, 0.5, 0.5]])
    ).tolist() == [False]


@pytest.mark.usefixtures("opengl")
def test_the_slicer_refuses_bricks_on_its_slices_path():
    volume = field_volume()
    layout = BrickLayout(volume.dimensions, volume.spacing, volume.origin, volume.value_range, 4)
    renderer = registry.create("slicer")
    try:
        renderer.set_settings(RenderSettings(options={"path": "slices"}))
        renderer.set_volume(volume)
        renderer.set_transfer_function(TF)
        renderer.set_region(layout.region(layout.brick_at((0, 0, 0))))
        with pytest.raises(VolrenError, match="path=march"):
            renderer.render(Camera.orbit(volume.bounds), 8, 8)
    finally:
        renderer.release()
