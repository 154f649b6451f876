"""Every built-in renderer declares its options once, as OptionSpecs, with the defaults it had when
each parsed its own; a renderer holds them parsed in `opts`."""

from __future__ import annotations

import pytest

from volren.model.settings import RenderSettings
from volren.renderers.base import option_help_of
from volren.renderers.registry import registry

#: Every built-in renderer's options and defaults as they were before the spec, when each parsed its
#: own (raycast's OPTIONS table, SlicerOptions, tetra's inline defaults, the reference's and vtk's).
BUILTIN_DEFAULTS = {
    "raycast": {"brick_size": 4, "empty_space_skipping": True, "termination_alpha": 0.999,
                "depth_offsets": "interleaved", "jitter_seed": 0, "table_size": 256, "classification_table": 4096,
                "image_stride": 1, "refine_tolerance": 0.02, "table_2d": 512, "target_error": 0.0},
    "slicer": {"path": "march", "table_size": 512, "empty_space_skipping": True, "early_termination": True,
               "termination_alpha": 0.999, "brick_size": 8, "jitter_seed": 1, "termination_interval": 16,
               "volume_format": "float"},
    "tetra": {"table_size": 256, "table_lengths": 32, "termination_alpha": 0.999, "max_steps": 100_000,
              "backend": "auto", "skip_transparent": True, "image_stride": 1, "refine_tolerance": 0.02},
    "reference": {"tolerance": 1e-5, "max_levels": 10},
    # None: by volume kind (auto on grids, raycast on tetrahedra)
    "vtk": {"mapper": None},
}  # fmt: skip


@pytest.mark.parametrize("name", sorted(BUILTIN_DEFAULTS))
def test_each_builtin_declares_its_former_options_and_defaults(name):
    cls = registry.get(name)
    assert {spec.name: spec.default for spec in cls.options} == BUILTIN_DEFAULTS[name]
    assert dict(cls.option_help) == option_help_of(cls.options)


@pytest.mark.parametrize("name, given", [("raycast", {"table_size": 64}), ("tetra", {"max_steps": 5}),
                                         ("reference", {"max_levels": 3})])  # fmt: skip
def test_a_renderer_holds_its_options_parsed_defaults_filled_in(name, given):
    renderer = registry.create(name)
    try:
        assert dict(renderer.opts) == BUILTIN_DEFAULTS[name]
        renderer.set_settings(RenderSettings(options=given))
        assert dict(renderer.opts) == {**BUILTIN_DEFAULTS[name], **given}
    finally:
        renderer.release()
