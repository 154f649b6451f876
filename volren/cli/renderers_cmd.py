"""`volren renderers`: the registered renderers, what each can draw, and what each `--quality`
level means for it (`volren.quality`'s measured table)."""

from __future__ import annotations

import argparse

from volren.errors import VolrenError


def add_parser(sub) -> None:
    parser = sub.add_parser("renderers", help="list registered renderers and their capabilities")
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from volren.model.scene_class import SceneClass
    from volren.model.tf_class import TFClass
    from volren.quality import LEVELS, table
    from volren.renderers.registry import registry

    quality = table()
    for name in registry.names():
        try:
            caps = registry.capabilities(name)
        except VolrenError as exc:
            print(f"{name:12s} UNAVAILABLE: {exc}")
            continue
        print(f"{name:12s} [{caps.backend}] {caps.describe()}")
        if caps.summary:
            print(f"{'':12s} {caps.summary}")
        for kind, support in sorted(caps.kinds.items()):
            acc = support.accuracy
            print(
                f"{'':12s} accuracy on {kind}: RMSE <= {acc.rmse:g}, features within {acc.position_px:g} px"
            )
        if caps.quality:
            print(f"{'':12s} quality axis: {' | '.join(level.label for level in caps.quality)}")
        for kind in sorted(caps.kinds):
            for scene in [SceneClass(kind), *(SceneClass(kind, cls) for cls in TFClass)]:
                if name not in quality.levels.get(scene, {}):
                    continue
                where = kind if scene.tf is None else f"{kind} with a {scene.tf.value} TF"
                for level in LEVELS:
                    c = quality.levels[scene][name][level]
                    print(f"{'':12s} --quality {level} on {where}: {c.level.label} (measured: "
                          f"{c.time_ratio(c.ms):.2g}x VTK's default's frame time, RMSE up to "
                          f"{c.worst_error_ratio:.2g}x its RMSE, over {len(c.ms)} scenes)")  # fmt: skip
        for key, text in registry.get(name).option_help.items():
            print(f"{'':12s} option {key}: {text}")
    return 0
