"""Table 1 of Schulze, Kraus, Lang and Ertl 2003 for `shearwarp`: seconds per 512x512 frame of the
standard shear-warp (post-classified, no opacity correction) against pre-integration with nearest
and bilinear table lookup, each with opacity correction off (NC) and on (OC).

    python -m benchmarks.shearwarp_table1 [--shared DIR] [--datasets engine,bonsai,HeadMRVolume]
                                         [--degrees 6] [--projections parallel,perspective]

The paper's protocol: the opacity a linear ramp from 0 to 1 over the data range (grey), the volume
turned 180 degrees about its vertical axis in steps (the paper: 2 degrees; `--degrees`), the mean
frame time; one intermediate pixel per voxel (`oversampling` 1), as the paper's intermediate image.
The paper's slice-buffer column (SB against IB) has no counterpart: this renderer keeps one
intermediate-image-sized buffer (IB). Under perspective, opacity correction means a table per
pixel's segment length (the seed measured parallel projection only). The machine's load average
is printed at the start and the end (timings share the cores with whatever else runs).
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

import numpy as np

from benchmarks.machine_speed import machine_line
from volren.api import prepared_renderer
from volren.bench.datasets import shared_datasets
from volren.io.volume_io import load_volume
from volren.model import Camera, RenderSettings, TransferFunction1D, UniformVolume

#: (column, preintegration, lookup, opacity correction), the paper's order.
COLUMNS = (
    ("standard", False, "nearest", False),
    ("post OC", False, "nearest", True),
    ("pre nearest NC", True, "nearest", False),
    ("pre nearest OC", True, "nearest", True),
    ("pre bilinear NC", True, "bilinear", False),
    ("pre bilinear OC", True, "bilinear", True),
)


def ramp_tf(volume: UniformVolume) -> TransferFunction1D:
    lo, hi = volume.value_range
    return TransferFunction1D([[lo, 1, 1, 1], [hi, 1, 1, 1]], [[lo, 0.0], [hi, 1.0]])


def transparent_fraction(volume: UniformVolume, tf: TransferFunction1D) -> float:
    values = np.asarray(volume.values, np.float64)
    _, alpha = tf.sample(values[np.isfinite(values)])
    return float(np.mean(alpha <= 0.0))


def load(shared: Path, name: str) -> UniformVolume:
    datasets = shared_datasets(shared)
    if name in datasets:
        volume = datasets[name].load()
    else:
        volume = load_volume(shared / "data" / "uniform" / f"{name}.mhd")
    assert isinstance(volume, UniformVolume)
    return volume


def frame_seconds(volume: UniformVolume, tf: TransferFunction1D, column: tuple, parallel: bool,
                  degrees: float) -> float:  # fmt: skip
    """Mean seconds per frame over a half turn about the vertical axis (after one untimed frame)."""
    _, pre, lookup, correction = column
    settings = RenderSettings(preintegration=pre, options={"oversampling": 1.0, "lookup": lookup,
                                                           "opacity_correction": correction})  # fmt: skip
    with prepared_renderer("shearwarp", volume, tf, settings) as renderer:
        renderer.render(Camera.orbit(volume.bounds, 0.0, 0.0, parallel=parallel), 512, 512)
        times = []
        for angle in np.arange(degrees, 180.0 + 1e-9, degrees):
            camera = Camera.orbit(volume.bounds, float(angle), 0.0, parallel=parallel)
            start = time.perf_counter()
            renderer.render(camera, 512, 512)
            times.append(time.perf_counter() - start)
    return statistics.fmean(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shared", type=Path, default=Path(os.environ.get("VOLREN_SHARED", "../shared")))
    parser.add_argument("--datasets", default="engine,bonsai,HeadMRVolume")
    parser.add_argument("--degrees", type=float, default=6.0)
    parser.add_argument("--projections", default="parallel,perspective")
    args = parser.parse_args()
    print(f"load average at the start: {' '.join(f'{x:.2f}' for x in os.getloadavg())}; {machine_line()}")
    header = " | ".join(c[0] for c in COLUMNS)
    print(f"| dataset | size | transparent | projection | {header} |")
    print("|---|---|---:|---|" + "---:|" * len(COLUMNS))
    for name in args.datasets.split(","):
        volume = load(args.shared, name)
        tf = ramp_tf(volume)
        nx, ny, nz = volume.dimensions
        for projection in args.projections.split(","):
            secs = [
                frame_seconds(volume, tf, column, projection == "parallel", args.degrees)
                for column in COLUMNS
            ]
            cells = " | ".join(f"{s:.3f}" for s in secs)
            print(f"| {name} | {nx}x{ny}x{nz} | {100 * transparent_fraction(volume, tf):.1f}% | {projection} | {cells} |",
                  flush=True)  # fmt: skip
    print(f"load average at the end: {' '.join(f'{x:.2f}' for x in os.getloadavg())}; {machine_line()}")


if __name__ == "__main__":
    main()
