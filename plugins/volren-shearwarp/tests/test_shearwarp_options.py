"""shearwarp declares its options once, as OptionSpecs, with the defaults it had when it parsed its own."""

from __future__ import annotations

from volren_shearwarp.renderer import ShearWarpRenderer

from volren.model.settings import RenderSettings
from volren.renderers.base import option_help_of

#: The options and defaults of shearwarp's former OPTIONS table.
FORMER_DEFAULTS = {
    "oversampling": "auto", "pixels_per_voxel": 1.0, "table_size": "auto", "lookup": "nearest", "warp_filter": "cubic",
    "empty_space_skipping": True, "early_termination": True, "termination_alpha": 0.995, "opacity_correction": True,
    "length_ratio": 1.02, "jitter_seed": 0, "downsample": 1,
}  # fmt: skip


def test_the_declared_specs_keep_the_former_defaults():
    assert {spec.name: spec.default for spec in ShearWarpRenderer.options} == FORMER_DEFAULTS
    assert dict(ShearWarpRenderer.option_help) == option_help_of(ShearWarpRenderer.options)


def test_the_renderer_holds_its_options_parsed():
    renderer = ShearWarpRenderer()
    assert dict(renderer.opts) == FORMER_DEFAULTS
    renderer.set_settings(RenderSettings(options={"oversampling": 2, "table_size": 64, "downsample": 4}))
    assert dict(renderer.opts) == {**FORMER_DEFAULTS, "oversampling": 2.0, "table_size": 64, "downsample": 4}
    assert type(renderer.opts["oversampling"]) is float
