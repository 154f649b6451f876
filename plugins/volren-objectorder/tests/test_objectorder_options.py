"""objectorder declares its options once, as OptionSpecs, with the defaults it had when it parsed its own."""

from __future__ import annotations

import pytest
from volren_objectorder.renderer import ObjectOrderRenderer

from volren.errors import VolrenError
from volren.model.settings import RenderSettings
from volren.renderers.base import option_help_of

#: The options and defaults of objectorder's former OPTIONS table.
FORMER_DEFAULTS = {
    "octree_skipping": True, "hidden_volume_removal": True, "termination_alpha": 0.999, "depth_offsets": "interleaved",
    "jitter_seed": 0, "table_size": 256, "classification_table": 4096, "band_rows": 32, "block_pixels": 36,
}  # fmt: skip


def test_the_declared_specs_keep_the_former_defaults():
    assert {spec.name: spec.default for spec in ObjectOrderRenderer.options} == FORMER_DEFAULTS
    assert dict(ObjectOrderRenderer.option_help) == option_help_of(ObjectOrderRenderer.options)


@pytest.mark.parametrize("table", [0, 16, 65536])
def test_the_classification_table_is_0_or_16_to_65536(table):
    renderer = ObjectOrderRenderer()
    renderer.set_settings(RenderSettings(options={"classification_table": table}))
    assert dict(renderer.opts) == {**FORMER_DEFAULTS, "classification_table": table}


@pytest.mark.parametrize("table", [1, 15, 65537, -1])
def test_other_classification_tables_are_refused_in_one_line(table):
    with pytest.raises(
        VolrenError, match=rf"option classification_table must be 0 or an integer in 16..65536, got {table}$"
    ):
        ObjectOrderRenderer().set_settings(RenderSettings(options={"classification_table": table}))
