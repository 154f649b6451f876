"""`volren prepare` (`volren.prepare`): every claimed combination drawn once, failures reported in one line."""

from __future__ import annotations

import numpy as np
import pytest

from volren.cli.main import main
from volren.model import BlendMode
from volren.prepare import prepare, prepare_renderer
from volren.renderers.base import Capabilities, KindSupport, RendererBase
from volren.renderers.registry import registry


class Counting(RendererBase):
    """Records what it was asked to draw."""

    name = "prepare-counting"
    capabilities = Capabilities(
        {"uniform": KindSupport(preintegration=True, blend_modes=frozenset({BlendMode.COMPOSITE, BlendMode.MAXIMUM})),
         "tet": KindSupport()},
        backend="test",
    )  # fmt: skip
    drawn: list = []

    def _render(self, camera, width, height, progress):
        Counting.drawn.append((self.volume.kind, self.volume.values.dtype, self.settings.preintegration,
                               self.settings.blend_mode, camera.parallel))  # fmt: skip
        return np.zeros((height, width, 4), np.float32), {}


class Broken(Counting):
    name = "prepare-broken"

    def _render(self, camera, width, height, progress):
        raise RuntimeError("kernel failed\nwith detail")


@pytest.fixture
def fakes():
    registry.register(Counting.name, Counting, replace=True)
    registry.register(Broken.name, Broken, replace=True)
    Counting.drawn = []
    yield
    registry.unregister(Counting.name)
    registry.unregister(Broken.name)


def test_every_claimed_combination_scalar_type_and_projection_is_drawn(fakes):
    result = prepare_renderer(Counting.name)
    assert result.error is None
    drawn = set(Counting.drawn)
    # uniform: 5 kept scalar types x (post, pre) x (composite, maximum) x 2 projections; tet: 1 x 2 projections
    assert result.frames == len(Counting.drawn) == 5 * 2 * 2 * 2 + 2
    assert {d[1] for d in drawn if d[0] == "uniform"} == {np.dtype(t) for t in ("uint8", "int16", "uint16", "float32", "float64")}
    assert {(d[2], d[3], d[4]) for d in drawn if d[0] == "uniform"} == {
        (pre, mode, parallel) for pre in (False, True) for mode in (BlendMode.COMPOSITE, BlendMode.MAXIMUM)
        for parallel in (False, True)}  # fmt: skip
    assert not any(d[2] for d in drawn if d[0] == "tet")  # not claimed there


def test_a_failing_renderer_is_reported_in_one_line_and_the_rest_still_prepared(fakes, capsys):
    seen = []
    results = prepare([Broken.name, Counting.name], seen.append)
    assert [r.name for r in results] == [r.name for r in seen] == [Broken.name, Counting.name]
    assert results[0].error == "RuntimeError: kernel failed with detail" and results[0].frames == 0
    assert results[1].error is None and results[1].frames > 0
    assert main(["prepare", "--renderers", f"{Broken.name},{Counting.name}"]) == 0
    out = capsys.readouterr().out
    assert f"prepare {Broken.name}: not prepared: RuntimeError: kernel failed with detail" in out
    assert f"prepare {Counting.name}: ready" in out


def test_an_unknown_name_is_a_one_line_error(capsys):
    assert main(["prepare", "--renderers", "nope"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "unknown renderer nope" in err
