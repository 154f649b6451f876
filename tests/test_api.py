"""volren.render: the same image from a model volume, a PyVista dataset and a file."""

from __future__ import annotations

import numpy as np
import pytest

import volren
from volren.api import default_transfer_function, parse_size
from volren.errors import VolrenError
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import UniformVolume

pytestmark = pytest.mark.usefixtures("opengl")


def test_model_volume_pyvista_dataset_and_file_render_alike(tmp_path):
    import pyvista as pv

    values = np.random.default_rng(1).random((10, 12, 14)).astype(np.float32)
    volume = UniformVolume(values, spacing=(1.0, 0.5, 2.0), origin=(1, 2, 3))
    grid = pv.ImageData(dimensions=volume.dimensions, spacing=volume.spacing, origin=volume.origin)
    grid.point_data["v"] = values.reshape(-1)  # x fastest, as VTK stores it
    path = tmp_path / "v.vti"
    grid.save(path)
    tf = TransferFunction1D.ramp(0, 1, 0.6, (1, 0.5, 0.2))
    kwargs = dict(size=(20, 16), azimuth=30, elevation=20, step=0.25)
    from_model = volren.render(volume, tf, **kwargs)
    assert from_model.shape == (16, 20, 4) and from_model[..., 3].max() > 0.2
    assert np.array_equal(volren.render(grid, tf, **kwargs), from_model)
    assert np.array_equal(volren.render(str(path), tf.to_dict(), **kwargs), from_model)


def test_default_transfer_function_spans_the_data():
    volume = UniformVolume(np.linspace(-5, 7, 27, dtype=np.float32).reshape(3, 3, 3), spacing=(2, 2, 2))
    tf = default_transfer_function(volume)
    assert tf.value_range == (-5.0, 7.0) and tf.opacity_unit_distance == 2.0
    assert (
        tf.sample([-5.0])[1][0] == 0.0 and tf.sample([7.0])[1][0] > 0.0
    )  # how much: tests/model/test_default_tf.py


@pytest.mark.parametrize(
    "size, expected", [(64, (64, 64)), ("640x480", (640, 480)), ((3, 5), (3, 5)), ("32", (32, 32))]
)
def test_parse_size(size, expected):
    assert parse_size(size) == expected


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"size": "big"}, "image size"),
        ({"size": (0, 4)}, "image size"),
        ({"stpe": 0.5}, "unknown render settings"),
        ({"azimuth": float("nan")}, "azimuth must be finite"),
        # integers beyond a float's range: not convertible, so not finite (was an OverflowError)
        ({"zoom": 10**400}, "zoom must be finite"),
        ({"step": 10**400}, "render setting step must be finite and positive"),
        ({"renderer": "nope"}, "unknown renderer"),
    ],
)
def test_bad_arguments_are_clear_errors(kwargs, message):
    volume = UniformVolume(np.zeros((2, 2, 2), np.uint8))
    with pytest.raises(VolrenError, match=message):
        volren.render(volume, **kwargs)


def test_default_transfer_function_of_values_near_the_float64_limits_is_finite():
    """hi - lo overflows to inf there; the control points must stay finite (they were refused)."""
    volume = UniformVolume(np.linspace(-1.0, 1.0, 8).reshape(2, 2, 2) * 1.7e308)
    tf = default_transfer_function(volume)
    assert tf.value_range == (-1.7e308, 1.7e308)
    assert np.isfinite(tf.color_points).all() and np.isfinite(tf.opacity_points).all()
    assert tf.sample([1.7e308])[1][0] > 0.0


@pytest.mark.vtk
def test_a_constant_fields_default_tf_draws_the_same_box_with_every_renderer():
    """Issue 23: the default TF of a constant field was a step at its value, which `reference`
    resolved as transparent and the others as opaque; now it is 0.3 there, unambiguously."""
    volume = UniformVolume(np.full((8, 8, 8), 5.0, np.float32))
    tf = default_transfer_function(volume)
    xs = tf.opacity_points[:, 0]
    assert np.all(np.diff(xs) > 0) and tf.sample([5.0])[1][0] == pytest.approx(0.3)
    kwargs = dict(size=(24, 24), azimuth=0, elevation=0, parallel=True, quality=None)
    alphas = {
        name: volren.render(volume, tf, renderer=name, **kwargs)[12, 12, 3]
        for name in ("reference", "vtk", "slicer")
    }
    expected = 1.0 - (1.0 - 0.3) ** 7  # 7 voxel spacings of 0.3 per spacing, through the middle
    for name, alpha in alphas.items():
        assert alpha == pytest.approx(expected, abs=0.03), (name, alphas)
