"""`volren renderers`: the registered renderers and what each can draw."""

from __future__ import annotations

import argparse

from volren.errors import VolrenError


def add_parser(sub) -> None:
    parser = sub.add_parser("renderers", help="list registered renderers and their capabilities")
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from volren.renderers.registry import registry

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
        for key, text in registry.get(name).option_help.items():
            print(f"{'':12s} option {key}: {text}")
    return 0
