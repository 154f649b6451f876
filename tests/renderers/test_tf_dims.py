"""The renderer contract for transfer-function dimensions: set_transfer_function and render check
the TF's dims against the capabilities, and a renderer without 2D support says so in one line."""

from __future__ import annotations

import numpy as np
import pytest

from volren.api import prepared_renderer
from volren.errors import VolrenError
from volren.model import Camera, TetVolume, TFWidget, TransferFunction1D, TransferFunction2D, UniformVolume
from volren.renderers.base import Capabilities, KindSupport, RendererBase
from volren.renderers.registry import registry

TF2 = TransferFunction2D((0.0, 1.0), (0.0, 1.0), [TFWidget.box((0.2, 0.8), (0.0, 1.0), (1.0, 1.0, 1.0), 0.5)])
GRID = UniformVolume(np.linspace(0, 1, 27).reshape(3, 3, 3))
TETS = TetVolume(np.eye(4, 3), np.array([[0, 1, 2, 3]]), np.ones(4))


class UniformOnly2D(RendererBase):
    name = "fake2d"
    capabilities = Capabilities(
        {"uniform": KindSupport(tf_dims=frozenset({1, 2})), "tet": KindSupport()}, backend="test"
    )

    def _render(self, camera, width, height, progress):
        return np.zeros((height, width, 4), np.float32), {}


def one_line(info) -> str:
    message = str(info.value)
    assert "\n" not in message
    return message


@pytest.mark.vtk
def test_vtk_refuses_a_2d_tf_in_one_line():
    with pytest.raises(VolrenError) as info:
        with prepared_renderer("vtk", GRID, TF2):
            pass
    assert one_line(info) == "renderer vtk does not support 2D transfer functions on uniform volumes"
    renderer = registry.create("vtk")
    try:
        with pytest.raises(VolrenError) as info:  # before any volume: no kind takes 2D
            renderer.set_transfer_function(TF2)
        assert one_line(info) == "renderer vtk does not support 2D transfer functions"
        assert renderer.transfer_function is None
    finally:
        renderer.release()


def test_render_checks_the_dims_of_the_tf_it_holds():
    r = UniformOnly2D()
    r.set_volume(GRID)
    r.set_transfer_function(TF2)
    assert r.render(Camera.orbit(GRID.bounds), 3, 2).shape == (2, 3, 4)
    r.set_volume(TETS)  # the volume changes under the 2D TF: the next frame says why it cannot
    with pytest.raises(VolrenError) as info:
        r.render(Camera.orbit(TETS.bounds), 3, 2)
    assert one_line(info) == "renderer fake2d does not support 2D transfer functions on tet volumes"
    r.set_transfer_function(TransferFunction1D.ramp(0, 1))
    r.render(Camera.orbit(TETS.bounds), 3, 2)
    with pytest.raises(VolrenError, match="needs a TransferFunction1D or TransferFunction2D, got dict"):
        r.set_transfer_function(TF2.to_dict())


def test_registry_and_capabilities_report_2d_support():
    compatible = registry.compatible("uniform", 2)
    assert compatible["reference"] is None and "2D" in compatible["vtk"]
    assert "2D" in registry.compatible("tet", 2)["reference"]


def test_no_renderer_claims_pre_integration_of_a_2d_tf():
    """The slicer pre-integrates 1D TFs only and refuses 2D ones: its capabilities must say so,
    so the app and the CLI never offer that combination (found by `volren bench stress`)."""
    from volren.model.settings import RenderSettings

    pre = RenderSettings(preintegration=True)
    assert registry.compatible("uniform", 1, pre)["slicer"] is None
    reasons = registry.compatible("uniform", 2, pre)
    assert "pre-integration of 2D transfer functions" in reasons["slicer"]
    assert registry.compatible("uniform", 2, RenderSettings())["slicer"] is None
