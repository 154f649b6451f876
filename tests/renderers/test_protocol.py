"""The Protocol says everything callers use: a renderer that implements it without subclassing
RendererBase works in `volren render`, `volren.render`, the bench and the app; the registry refuses
classes that lack a part of it."""

from __future__ import annotations

import numpy as np
import pytest

from tests.renderers.protocol_renderer import PlainRenderer
from volren.api import render
from volren.bench import run_bench, sweep
from volren.cli.main import main
from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.renderers.base import Renderer, RendererBase, render_frame
from volren.renderers.registry import RendererRegistry, check_renderer_class, registry
from volren.samples import marschner_lobb, sample_transfer_functions


@pytest.fixture
def plain():
    registry.register("plain", PlainRenderer, replace=True)
    yield "plain"
    registry.unregister("plain")


def test_the_plain_renderer_is_not_a_renderer_base_but_is_a_renderer():
    assert not issubclass(PlainRenderer, RendererBase)
    assert isinstance(PlainRenderer(), Renderer)
    check_renderer_class(PlainRenderer, "plain")


def test_volren_render_and_the_api(plain, tmp_path, capsys):
    volume = marschner_lobb(9)
    image = render(volume, renderer=plain, size=(6, 4))
    assert image.shape == (4, 6, 4) and np.allclose(image[..., 3], 0.5)
    from volren.io import save_volume

    path = tmp_path / "v.vti"
    save_volume(volume, path)
    out = tmp_path / "out.png"
    assert (
        main(
            [
                "render",
                str(path),
                "-o",
                str(out),
                "--renderer",
                plain,
                "--size",
                "8",
                "--option",
                "alpha=0.25",
            ]
        )
        == 0
    )
    assert out.exists()
    assert capsys.readouterr().out.startswith("plain: 8x8 in ")


def test_the_bench_sweeps_its_quality_axis(plain):
    configs = sweep.configs("uniform", curves=[plain])
    assert [c.label for c in configs] == ["coarse", "fine"] and [c.settings().step for c in configs] == [
        1.0,
        0.25,
    ]
    assert sweep.configs("tet", curves=[plain]) == []
    volume = marschner_lobb(9)
    tf = sample_transfer_functions()["marschner_lobb"]
    reference = np.zeros((8, 8, 4), np.float32)
    row = run_bench.measure(
        configs[0], volume, tf, lambda a: Camera.orbit(volume.bounds, a), reference, 8, 3, 2.0
    )
    assert row["renderer"] == plain and row["settings"] == "coarse" and row["samples"] == 64
    assert row["rmse"] > 0


def test_unknown_bench_renderers_are_named():
    with pytest.raises(VolrenError, match="registered renderer"):
        sweep.check_curves(["nosuch"])


class _NoOptionHelp(PlainRenderer):
    option_help = None


class _NoOptionSpecs(PlainRenderer):
    options = {"alpha": 0.5}


class _NoLastFrame(PlainRenderer):
    def __init__(self) -> None:
        super().__init__()
        del self.last_frame


def test_the_registry_checks_the_whole_protocol():
    with pytest.raises(VolrenError, match="option_help"):
        check_renderer_class(_NoOptionHelp, "x")
    with pytest.raises(VolrenError, match="no `options` tuple of OptionSpec"):
        check_renderer_class(_NoOptionSpecs, "x")
    reg = RendererRegistry(entry_points=lambda: [], builtin_fallback=False)
    reg.register("nolast", _NoLastFrame)
    with pytest.raises(VolrenError, match="last_frame"):
        reg.create("nolast")


def test_render_frame_refuses_a_wrong_image_or_missing_stats():
    class WrongShape(PlainRenderer):
        def render(self, camera, width, height, progress=None):
            super().render(camera, width, height, progress)
            return np.zeros((width, height, 3), np.float32)

    class NoStats(PlainRenderer):
        def render(self, camera, width, height, progress=None):
            image = super().render(camera, width, height, progress)
            self.last_frame = None
            return image

    volume = marschner_lobb(9)
    for cls, message in ((WrongShape, "returned float32 \\(4, 3, 3\\)"), (NoStats, "last_frame")):
        r = cls()
        r.set_volume(volume)
        r.set_transfer_function(sample_transfer_functions()["marschner_lobb"])
        with pytest.raises(VolrenError, match=message):
            render_frame(r, Camera.orbit(volume.bounds), 4, 3)
