"""`volren prepare [--renderers A,B] [--jobs N]`: compile every renderer's kernels ahead of the first
frame (`volren.prepare`), N renderers at once (default: one per core); `scripts/setup.sh` runs it
whenever the sources change.

Prints one line per renderer (seconds, frames, or the error that stopped it) with a progress bar
over the renderers on a terminal; exits 0 even when a renderer could not be prepared (a machine
without OpenGL still gets its CPU renderers ready), 1 only for an unknown renderer name.
"""

from __future__ import annotations

import argparse


def add_parser(sub) -> None:
    p = sub.add_parser("prepare", help="compile the renderers' kernels now, so that first frames do not wait")
    p.add_argument("--renderers", help="comma-separated registered names (default: all)")
    p.add_argument(
        "--jobs",
        type=int,
        default=None,
        metavar="N",
        help="renderers prepared at once, each in its own process (default: one per core)",
    )
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from volren.errors import VolrenError
    from volren.prepare import default_jobs, prepare
    from volren.renderers.registry import registry

    names = (
        registry.names()
        if not args.renderers
        else [n.strip() for n in args.renderers.split(",") if n.strip()]
    )
    unknown = [n for n in names if n not in registry.names()]
    if unknown:
        raise VolrenError(
            f"--renderers: unknown renderer {', '.join(unknown)} (registered: {', '.join(registry.names())})"
        )
    if args.jobs is not None and args.jobs < 1:
        raise VolrenError(f"--jobs: must be at least 1, not {args.jobs}")
    bar = tqdm(total=len(names), desc="preparing renderers", unit="renderer", leave=False, disable=None)

    def done(result) -> None:
        bar.update(1)
        state = f"not prepared: {result.error}" if result.error else "ready"
        tqdm.write(f"prepare {result.name}: {state} ({result.frames} frames, {result.seconds:.1f} s)")

    try:
        prepare(names, done, jobs=args.jobs if args.jobs is not None else default_jobs())
    finally:
        bar.close()
    return 0
