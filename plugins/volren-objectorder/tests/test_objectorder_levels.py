"""The measured quality levels this plugin ships with itself (`volren.quality`): found through its
entry point, and every one a configuration of its own declared quality axis, so the levels name
nothing the plugin does not define."""

from volren import quality
from volren.model.scene_class import SceneClass
from volren.model.tf_class import TFClass
from volren.renderers.registry import registry


def test_the_shipped_levels_are_configurations_of_the_declared_quality_axis():
    path = registry.data_file("objectorder", quality.LEVELS_FILE)
    assert path is not None and path.parent.name == "volren_objectorder"
    table = quality.read_levels("objectorder", path)
    assert set(table.levels) == {SceneClass("uniform", cls) for cls in (None, *TFClass)}
    axis = {level.label: level for level in registry.capabilities("objectorder").quality}
    for scene, per in table.levels.items():
        assert list(per["objectorder"]) == list(quality.LEVELS), scene
        for measured in per["objectorder"].values():
            declared = axis.get(measured.level.label)
            assert declared is not None and declared.apply() == measured.level.apply(), measured.level.label
            assert set(measured.peer_ms) == set(measured.ms)  # a peer time for every scene measured
