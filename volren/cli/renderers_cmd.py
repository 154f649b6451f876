"""`volren renderers`: the registered renderers, what each can draw, and what each `--quality`
level means for it (`volren.quality`'s measured table)."""

from __future__ import annotations

import argparse

from volren.errors import VolrenError


def add_parser(sub) -> None:
    parser = sub.add_parser("renderers", help="list registered renderers and their capabilities")
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from volren.quality import LEVELS, TF_CLASSES, table
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
            print(f"{'':12s} accuracy on {kind}: RMSE <= {acc.rmse:g}, features within {acc.position_px:g} px")
        if caps.quality:
            print(f"{'':12s} quality axis: {' | '.join(level.label for level in caps.quality)}")
        for kind in sorted(caps.kinds):
            for scene_kind in [kind, *(f"{kind}/{cls}" for cls in TF_CLASSES)]:
                if scene_kind not in quality.levels or name not in quality.levels[scene_kind]:
                    continue
                where = kind if scene_kind == kind else f"{kind} with a {scene_kind.split('/')[1]} TF"
                for level in LEVELS:
                    c = quality.levels[scene_kind][name][level]
                    mean_ms = sum(c.ms.values()) / len(c.ms)
                    print(f"{'':12s} --quality {level} on {where}: {c.label} (measured: {mean_ms:.0f} ms a 512x512 "
                          f"frame on average, RMSE up to {c.worst_error_ratio:.2g}x VTK's default's over {len(c.ms)} "
                          f"scenes)")  # fmt: skip
        for key, text in registry.get(name).option_help.items():
            print(f"{'':12s} option {key}: {text}")
    return 0
