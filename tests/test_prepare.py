"""`volren prepare` (`volren.prepare`): every claimed combination drawn once, failures reported in one line."""

from __future__ import annotations

import faulthandler
import os

import numpy as np
import pytest

from volren.cli.main import main
from volren.errors import VolrenError
from volren.model import BlendMode, RenderSettings
from volren.prepare import _prepare_in_processes, _volumes, prepare, prepare_renderer
from volren.renderers.base import Capabilities, KindSupport, OptionSpec, QualityLevel, RendererBase
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


class Leveled(Counting):
    """A quality axis whose refined level applies to grids only."""

    name = "prepare-leveled"
    capabilities = Capabilities(
        {"uniform": KindSupport(), "tet": KindSupport()}, backend="test",
        quality=(QualityLevel("coarse", step=2.0), QualityLevel("refined", options={"image_stride": 4})),
    )  # fmt: skip

    options = (OptionSpec("image_stride", 1, "int", "rays every so many pixels", low=1),)

    def _parse_options(self, options):
        if "image_stride" in options and self.volume is not None and self.volume.kind == "tet":
            raise VolrenError("renderer prepare-leveled: option image_stride is for grids")
        return super()._parse_options(options)

    def _render(self, camera, width, height, progress):
        Counting.drawn.append((self.volume.kind, self.settings.step, dict(self.settings.options)))
        return np.zeros((height, width, 4), np.float32), {}


class Mixing(Counting):
    """Claims label volumes and channels: what the drawn frames carry."""

    name = "prepare-mixing"
    capabilities = Capabilities({"uniform": KindSupport(labels=True, channels=True)}, backend="test")

    refuse_wide = False

    def _render(self, camera, width, height, progress):
        labels, channels = self.volume.labels, self.volume.channels
        if self.refuse_wide and labels is not None and labels.max_label > 255:
            raise VolrenError("renderer prepare-mixing draws labels up to 255 only")
        Counting.drawn.append((type(self.transfer_function).__name__, self.volume.values.dtype,
                               None if labels is None else labels.values.dtype,
                               None if channels is None else channels.values.shape[0], self.settings.preintegration))  # fmt: skip
        return np.zeros((height, width, 4), np.float32), {}


@pytest.fixture
def fakes():
    for cls in (Counting, Broken, Leveled, Mixing):
        registry.register(cls.name, cls, replace=True)
    Counting.drawn = []
    yield
    for cls in (Counting, Broken, Leveled, Mixing):
        registry.unregister(cls.name)


def test_every_claimed_combination_scalar_type_and_projection_is_drawn(fakes):
    result = prepare_renderer(Counting.name)
    assert result.error is None
    drawn = set(Counting.drawn)
    # uniform: 5 kept scalar types x (post, pre) x (composite, maximum) x 2 projections; tet: 1 x 2 projections
    assert result.frames == len(Counting.drawn) == 5 * 2 * 2 * 2 + 2
    assert {d[1] for d in drawn if d[0] == "uniform"} == {
        np.dtype(t) for t in ("uint8", "int16", "uint16", "float32", "float64")
    }
    assert {(d[2], d[3], d[4]) for d in drawn if d[0] == "uniform"} == {
        (pre, mode, parallel) for pre in (False, True) for mode in (BlendMode.COMPOSITE, BlendMode.MAXIMUM)
        for parallel in (False, True)}  # fmt: skip
    assert not any(d[2] for d in drawn if d[0] == "tet")  # not claimed there


def test_label_volumes_in_each_label_type_and_channels_are_drawn_where_claimed(fakes):
    """A label volume's march and a multi-channel march are kernels of their own (and compile per
    label type): each scalar type gets both label types and the channels, post-classified."""
    assert prepare_renderer(Mixing.name).error is None
    mixed = [d for d in Counting.drawn if d[0] != "TransferFunction1D"]
    scalar_types = {np.dtype(t) for t in ("uint8", "int16", "uint16", "float32", "float64")}
    labels = {(d[1], d[2]) for d in mixed if d[0] == "LabelTransferFunction"}
    assert labels == {(s, np.dtype(t)) for s in scalar_types for t in ("uint8", "uint16")}
    assert {(d[1], d[3]) for d in mixed if d[0] == "ChannelTransferFunction"} == {
        (s, 2) for s in scalar_types
    }
    assert len(mixed) == 5 * 3 * 2 and not any(d[4] for d in mixed)  # both projections, none pre-integrated
    # a label type refused at render time (vtk's 8-bit mask) is passed over, not an error
    Counting.drawn = []
    Mixing.refuse_wide = True
    try:
        assert prepare_renderer(Mixing.name).error is None
    finally:
        Mixing.refuse_wide = False
    assert {d[2] for d in Counting.drawn if d[0] == "LabelTransferFunction"} == {np.dtype("uint8")}
    # a renderer that claims neither draws neither
    Counting.drawn = []
    assert prepare_renderer(Counting.name).error is None
    assert all(d[0] == "uniform" or d[0] == "tet" for d in Counting.drawn)


def test_every_quality_level_is_drawn_where_it_applies(fakes):
    """A level's options reach kernels the default settings do not (adaptive refinement): each
    level is drawn too, and one the volume's kind refuses is passed over, not an error."""
    result = prepare_renderer(Leveled.name)
    assert result.error is None and result.frames == len(Counting.drawn)
    default_step = RenderSettings().step
    levels = [(kind, step, options.get("image_stride")) for kind, step, options in Counting.drawn
              if step != default_step or options]  # fmt: skip
    # uniform: 5 scalar types x 2 levels x 2 projections; tet: the coarse level only, 2 projections
    assert len(levels) == 5 * 2 * 2 + 2
    assert set(levels) == {("uniform", 2.0, None), ("uniform", default_step, 4), ("tet", 2.0, None)}


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


def test_renderers_are_prepared_at_once_in_worker_processes(fakes):
    """jobs > 1: the entry points' renderers in spawned workers, one registered at run time (which a
    worker does not know) here; results in the order asked, each reported as it finishes."""
    seen = []
    results = prepare(["example", Counting.name], seen.append, jobs=2)
    assert [r.name for r in results] == ["example", Counting.name]
    assert sorted(r.name for r in seen) == sorted(["example", Counting.name])
    assert all(r.error is None and r.frames > 0 for r in results)
    assert len(Counting.drawn) == results[1].frames  # drawn in this process


def test_a_worker_process_that_dies_is_reported_for_its_renderers():
    """A crash (here a segfault) in a worker breaks the pool: the renderers it leaves are reported
    as not prepared, and set-up goes on."""
    seen = []
    results = _prepare_in_processes(["example", "reference"], seen.append, 2, work=faulthandler._sigsegv)
    assert [r.name for r in results] == ["example", "reference"] and len(seen) == 2
    assert all(r.frames == 0 and r.error.startswith("worker process failed: ") for r in results)


def test_jobs_below_one_is_a_one_line_error(capsys):
    assert main(["prepare", "--renderers", "example", "--jobs", "0"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--jobs: must be at least 1" in err


def test_a_renderer_that_draws_with_c_kernels_compiles_their_numba_stand_ins_too():
    """raycast's frames (1D and 2D TFs) draw with its C march where a compiler is found: prepare draws
    its scenes again with the C kernels off, so that numba's marches, which grids the C march cannot
    take draw with, are compiled at set-up too; the environment is left as it was."""
    from volren.kernels import native
    from volren.renderers.raycast import march_native

    if march_native._library() is None:
        pytest.skip("no C compiler here: there is one pass")
    seen = []
    real = march_native.kernels

    def spy(values, kind="1d"):
        found = real(values, kind)
        seen.append((kind, found is not None))
        return found

    before = os.environ.get("VOLREN_NATIVE")
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(march_native, "kernels", spy)
        patch.setattr("volren.prepare._volumes", lambda kind: iter([next(_volumes(kind))]))
        result = prepare_renderer("raycast")
    assert result.error is None
    for kind in ("1d", "2d"):  # frames with the C march, then with numba's, for both TF dimensions
        assert (kind, True) in seen and (kind, False) in seen
    assert os.environ.get("VOLREN_NATIVE") == before
    assert native.handed_out() > 0
