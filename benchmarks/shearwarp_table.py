"""`shearwarp` on the shared uniform scenes at 512x512: RMSE against `reference` (cached) and the
median of warm frames with the camera turning 2 degrees of azimuth per frame.

    python -m benchmarks.shearwarp_table [DATASETS] [STYLES] [CONFIGS_JSON] [FRAMES]

CONFIGS_JSON is a list of {"step": S, "pre": bool, <renderer options>}; docs/shearwarp.md holds a run.
The shared folder is $VOLREN_SHARED (default ../shared); reference images are cached as
volren.testing.reference_images does."""

import json
import os
import sys
from pathlib import Path

import numpy as np
from volren_shearwarp import ShearWarpRenderer

from volren.bench.datasets import shared_datasets
from volren.model import RenderSettings
from volren.testing import image_error
from volren.testing.reference_images import reference_image


def main():
    names = sys.argv[1].split(",") if len(sys.argv) > 1 else ["ironProt", "bonsai", "engine", "aneurism"]
    styles = sys.argv[2].split(",") if len(sys.argv) > 2 else ["smooth", "spiky", "opaque"]
    configs = json.loads(sys.argv[3]) if len(sys.argv) > 3 else [{}]
    frames = int(sys.argv[4]) if len(sys.argv) > 4 else 3
    ds = shared_datasets(Path(os.environ.get("VOLREN_SHARED", "../shared")))
    for name in names:
        d = ds[name]
        vol = d.load()
        r = ShearWarpRenderer()
        r.set_volume(vol)
        for style, tf in d.transfer_functions():
            if style not in styles:
                continue
            ref = reference_image(vol, tf, d.camera(vol.bounds), 512, 512)
            r.set_transfer_function(tf)
            for cfg in configs:
                cfg = dict(cfg)
                s = RenderSettings(
                    step=cfg.pop("step", 0.5), preintegration=cfg.pop("pre", False), options=cfg
                )
                r.set_settings(s)
                img = r.render(d.camera(vol.bounds), 512, 512)
                err = image_error(img, ref)
                times = []
                for f in range(frames):
                    r.render(d.camera(vol.bounds, turn=2.0 * (f + 1)), 512, 512)
                    times.append(r.last_frame.ms)
                c = r.last_frame.counters
                print(
                    f"{name:9s} {style:7s} step {s.step:g} {'pre ' if s.preintegration else 'post'} {json.dumps(s.options):40s} "
                    f"RMSE {err.rmse:.5f} max {err.max_abs:.3f}  ms median {np.median(times):7.1f} "
                    f"samples {c['samples']:.3g} inter {c['intermediate_width']:.0f}x{c['intermediate_height']:.0f} tl {c.get('table_lengths')}",
                    flush=True,
                )
        r.release()


if __name__ == "__main__":
    main()
