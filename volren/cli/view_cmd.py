"""`volren view [INPUT]`: the desktop app (imports Qt only when run; Qt is the `app` extra)."""

from __future__ import annotations

import argparse

from volren.cli.render_cmd import memory_size
from volren.extras import require


def add_parser(sub) -> None:
    p = sub.add_parser("view", help="open the desktop app (a bundled sample when no INPUT)")
    p.add_argument("input", nargs="?", help="volume file, DICOM folder or scene JSON")
    p.add_argument("--tf", help="transfer function JSON")
    p.add_argument("--scalars", help="name of the point array to render")
    p.add_argument(
        "--renderer",
        help="renderer to start with (default auto: the fastest measured renderer that draws "
        "the volume; a scene file's renderer when it names one)",
    )
    p.add_argument("--memory", type=memory_size, metavar="SIZE",
                   help="for an OME-Zarr INPUT: the most its levels may take in memory, e.g. 2GB (default 8GB); the "
                        "app opens the coarsest level and refines up to the finest within it")  # fmt: skip
    p.add_argument(
        "--screenshot",
        metavar="OUT.png",
        help="wait for the first full-quality frame, save a screenshot of the window and exit",
    )
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from volren.io.safe_write import refuse_overwriting_inputs

    refuse_overwriting_inputs(
        [("--screenshot", args.screenshot)], [("input", args.input), ("--tf file", args.tf)]
    )
    require("app", "volren view")
    from volren.app import main as app_main  # the CLI's one way into the app (pyproject.toml's contracts)

    return app_main.run(
        args.input,
        tf=args.tf,
        scalars=args.scalars,
        renderer=args.renderer,
        screenshot=args.screenshot,
        memory=args.memory,
        traceback=args.traceback,
    )
