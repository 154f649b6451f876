"""`volren prepare [--renderers A,B]`: compile every renderer's kernels ahead of the first frame
(`volren.prepare`); `scripts/setup.sh` runs it whenever the sources change.

Prints one line per renderer (seconds, frames, or the error that stopped it) with a progress bar
over the renderers on a terminal; exits 0 even when a renderer could not be prepared (a machine
without OpenGL still gets its CPU renderers ready), 1 only for an unknown renderer name.
"""

from __future__ import annotations

import argparse


def add_parser(sub) -> None:
    p = sub.add_parser("prepare", help="compile the renderers' kernels now, so that first frames do not wait")
    p.add_argument("--renderers", help="comma-separated registered names (default: all)")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from volren.errors import VolrenError
    from volren.prepare import prepare
    from volren.renderers.registry import registry

    names = registry.names() if not args.renderers else [n.strip() for n in args.renderers.split(",") if n.strip()]
    unknown = [n for n in names if n not in registry.names()]
    if unknown:
        raise VolrenError(f"--renderers: unknown renderer {', '.join(unknown)} (registered: {', '.join(registry.names())})")
    bar = tqdm(total=len(names), desc="preparing renderers", unit="renderer", leave=False, disable=None)

    def done(result) -> None:
        bar.update(1)
        state = f"not prepared: {result.error}" if result.error else "ready"
        tqdm.write(f"prepare {result.name}: {state} ({result.frames} frames, {result.seconds:.1f} s)")

    try:
        prepare(names, done)
    finally:
        bar.close()
    return 0
