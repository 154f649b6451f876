"""`volren demo`: render every bundled sample with every renderer that can draw it.

This is the README's main job on a machine without a display: it shows that the installation
works end to end and how long each renderer takes here. Each renderer draws two frames: the
first pays for set-up (GL context, uploads, compilation), the second (the camera turned by 10
degrees) is the time per frame, and is the one saved.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from volren.errors import VolrenError


def add_parser(sub) -> None:
    p = sub.add_parser("demo", help="render the bundled samples with every renderer (offscreen)")
    p.add_argument("--out", default="out/demo", help="folder for the PNGs (default out/demo)")
    p.add_argument("--size", default="256", help="image size W or WxH (default 256)")
    p.add_argument("--renderers", help="comma-separated renderer names (default: all registered)")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from volren import io
    from volren.api import parse_size, prepared_renderer
    from volren.cli.progress import progress_bar
    from volren.model.camera import Camera
    from volren.renderers.base import render_frame
    from volren.renderers.registry import registry
    from volren.samples import SAMPLES, sample_paths

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    width, height = parse_size(args.size)
    names = args.renderers.split(",") if args.renderers else registry.names()
    failures = 0
    for sample in SAMPLES:
        volume_path, tf_path = sample_paths(sample)
        volume = io.load_volume(volume_path)
        tf = io.load_transfer_function(tf_path)
        camera = Camera.orbit(volume.bounds, 30.0, 20.0, 1.0, aspect=width / height)
        for name in names:
            try:
                reason = registry.capabilities(name).unsupported_reason(volume.kind)
            except VolrenError as exc:
                print(f"{sample:16s} {name:10s} unavailable: {exc}")
                failures += 1
                continue
            if reason:
                print(f"{sample:16s} {name:10s} skipped: {reason}")
                continue
            target = out / f"{sample}_{name}.png"
            try:
                with prepared_renderer(name, volume, tf) as renderer:
                    with progress_bar(f"{sample} {name}") as progress:
                        _, first = render_frame(
                            renderer, camera.azimuth(-10.0), width, height, progress, name
                        )
                    image, stats = render_frame(renderer, camera, width, height, label=name)
                first_ms, ms = first.ms, stats.ms
            except VolrenError as exc:
                print(f"{sample:16s} {name:10s} FAILED: {exc}")
                failures += 1
                continue
            io.save_image(image, target)
            print(
                f"{sample:16s} {name:10s} {ms:9.1f} ms per frame (first {first_ms:.0f} ms with set-up)  {target}"
            )
    return 1 if failures else 0
