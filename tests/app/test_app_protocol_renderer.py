"""The app's render thread works with a renderer that follows the Protocol without RendererBase."""

from __future__ import annotations

import pytest

from tests.renderers.protocol_renderer import PlainRenderer
from volren.model.camera import Camera
from volren.samples import marschner_lobb, sample_transfer_functions


@pytest.mark.qt
def test_the_app_renders_it(qtbot):
    from volren.app.rendering.render_service import RenderService
    from volren.model.settings import RenderSettings

    service = RenderService(factory=lambda name: PlainRenderer())
    volume = marschner_lobb(9)
    frames = []
    service.frameReady.connect(frames.append)
    try:
        with qtbot.waitSignal(service.frameReady, timeout=5000):
            service.submit("plain", volume, sample_transfer_functions()["marschner_lobb"], RenderSettings(),
                           Camera.orbit(volume.bounds), 8, 6)  # fmt: skip
    finally:
        service.shutdown()
    assert frames[-1].rgb.shape == (6, 8, 3) and frames[-1].ms == 1.0
