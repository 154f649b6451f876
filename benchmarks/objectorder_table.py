"""`objectorder` on the shared uniform scenes, parallel projection: RMSE against `reference` next to
the slicer's post-classified march at the same step, and Mora et al.'s Table 1 counters and the median
of warm 512x512 frames (camera turning 2 degrees of azimuth per frame) with hidden volume removal
on and off.

    python -m benchmarks.objectorder_table [DATASETS] [STYLES] [ERROR_SIZE] [FRAMES]

The cached reference images of the shared scenes are for their perspective cameras; the parallel
ones are rendered here (and cached as volren.testing.reference_images does, $VOLREN_REFERENCE_CACHE)
at ERROR_SIZE x ERROR_SIZE (default 256: the float64 reference is slow), and the RMSE of both
renderers is taken at that size. FRAMES (default 5) warm frames per median; the machine's load
average is printed at the start and the end (the timings share the cores with whatever else runs).
docs/objectorder.md holds a run. The shared folder is
$VOLREN_SHARED (default ../shared)."""

import os
import sys
from pathlib import Path

import numpy as np
from volren_objectorder import ObjectOrderRenderer

from benchmarks.machine_speed import machine_line
from volren.api import prepared_renderer
from volren.bench.datasets import shared_datasets
from volren.model import Camera, RenderSettings
from volren.testing import image_error
from volren.testing.reference_images import reference_image


def parallel_camera(d, bounds, turn: float = 0.0) -> Camera:
    return Camera.orbit(bounds, d.azimuth + turn, d.elevation, d.zoom, parallel=True)


def main() -> None:
    names = sys.argv[1].split(",") if len(sys.argv) > 1 else ["ironProt", "bonsai", "engine", "aneurism"]
    styles = sys.argv[2].split(",") if len(sys.argv) > 2 else ["smooth", "spiky", "opaque"]
    size = int(sys.argv[3]) if len(sys.argv) > 3 else 256
    frames = int(sys.argv[4]) if len(sys.argv) > 4 else 5
    ds = shared_datasets(Path(os.environ.get("VOLREN_SHARED", "../shared")))
    settings = RenderSettings(step=0.5)
    print(
        "load average (1, 5, 15 min) at the start: {:.2f} {:.2f} {:.2f}".format(*os.getloadavg()), flush=True
    )
    print(machine_line(), flush=True)
    print(f"{'scene':17s} {'RMSE oo':>8s} {'RMSE slicer':>11s} | {'HVR':3s} {'ms':>7s} {'cells':>8s} {'occluded':>8s} "
          f"{'nodes':>8s} {'samples':>9s} {'Mcells/s':>8s}", flush=True)  # fmt: skip
    for name in names:
        d = ds[name]
        vol = d.load()
        r = ObjectOrderRenderer()
        r.set_volume(vol)
        for style, tf in d.transfer_functions():
            if style not in styles:
                continue
            camera = parallel_camera(d, vol.bounds)
            ref = reference_image(vol, tf, camera, size, size, settings)
            with prepared_renderer("slicer", vol, tf, settings) as slicer:
                e_slicer = image_error(slicer.render(camera, size, size), ref).rmse
            r.set_transfer_function(tf)
            r.set_settings(settings)
            e_oo = image_error(r.render(camera, size, size), ref).rmse
            rows = []
            for hvr in (True, False):
                r.set_settings(settings.with_(options={"hidden_volume_removal": hvr}))
                r.render(camera, 512, 512)  # warm: classification and tables
                times, counters = [], []
                for f in range(frames):
                    r.render(parallel_camera(d, vol.bounds, 2.0 * (f + 1)), 512, 512)
                    times.append(r.last_frame.ms)
                    counters.append(r.last_frame.counters)
                ms = float(np.median(times))
                c = counters[int(np.argsort(times)[len(times) // 2])]
                rows.append((hvr, ms, c))
            for hvr, ms, c in rows:
                head = f"{name + ' ' + style:17s} {e_oo:8.5f} {e_slicer:11.5f}" if hvr else " " * 38
                print(f"{head} | {'on' if hvr else 'off':3s} {ms:7.0f} {c['cells'] / 1e3:7.0f}K {c['occluded_ratio']:8.1%} "
                      f"{c['nodes'] / 1e3:7.0f}K {c['samples'] / 1e3:8.0f}K {c['cells'] / ms / 1e3:8.2f}", flush=True)  # fmt: skip
            print(f"{'':17s} speedup with hidden volume removal: {rows[1][1] / rows[0][1]:.2f}x", flush=True)
        r.release()
    print("load average (1, 5, 15 min) at the end: {:.2f} {:.2f} {:.2f}".format(*os.getloadavg()), flush=True)
    print(machine_line(), flush=True)


if __name__ == "__main__":
    main()
