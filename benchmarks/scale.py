"""`python -m benchmarks.scale`: time and peak memory against volume size, one process against a
LocalCluster of 1 and 2 workers, the share of compositing, and a model of compositing for 8 to
1024 workers built on the per-layer costs measured here.

Volumes: `benchmarks.procedural` (Marschner-Lobb in a sphere), n^3 uint16, written once into OME-Zarr
pyramids of 64^3 bricks under --data (kept between runs). For each size:
- one process streams the full resolution and the level of detail the view picks, brick by brick
  within --memory, each in a fresh process (`scale_probe`) whose peak resident memory is read;
- for --cluster-size (a volume that fits), a LocalCluster of 1 and of 2 workers (one thread
  each) draws the full resolution; frames per second and the share of the client's final
  composite in the frame.

The compositing model (IceT's three strategies) takes three measured costs: `over` per pixel,
moving a layer between processes per byte, and a message's latency.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from benchmarks._cli import run
from benchmarks.procedural import ProceduralVolume
from benchmarks.scale_scene import scale_camera, scale_settings, scale_tf
from volren.errors import VolrenError

CHUNK = 64
COMMAND = "python -m benchmarks.scale"
#: The repository root, on the probe's path wherever the benchmark was started from.
ROOT = Path(__file__).resolve().parents[1]


def ensure_volume(folder: Path, n: int) -> Path:
    """folder/ml{n}.zarr, written (with a progress bar) unless it is there."""
    from volren.cli.progress import progress_bar
    from volren.io.ome_zarr_io import write_pyramid

    path = folder / f"ml{n}.zarr"
    if not path.is_dir():
        folder.mkdir(parents=True, exist_ok=True)
        volume = ProceduralVolume(n)
        with progress_bar(f"writing {path.name}") as progress:
            write_pyramid(volume, volume.spacing, volume.origin, f"ml{n}", path, CHUNK, progress=progress)
    return path


def probe(path: Path, level: int, memory: int, size: int, frames: int, renderer: str) -> dict:
    """`scale_probe` in a fresh process: its frames, peak memory and counters."""
    command = [sys.executable, "-m", "benchmarks.scale_probe", str(path), str(level), str(memory), str(size),
               str(frames), renderer]  # fmt: skip
    env = dict(
        os.environ, PYTHONPATH=os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH")) if p)
    )
    done = subprocess.run(command, capture_output=True, text=True, check=False, env=env)
    if done.returncode != 0:
        raise VolrenError(
            f"scale probe of {path.name} level {level} failed: {done.stderr.strip().splitlines()[-1:]}"
        )
    return json.loads(done.stdout.strip().splitlines()[-1])


def cluster_frames(path: Path, workers: int, size: int, frames: int, renderer: str, memory: int) -> dict:
    """Frames of level 0 on a new LocalCluster of `workers`: times, composite share, worker times."""
    from volren.bricked.cluster import ClusterRenderer, ZarrSpec, local_client
    from volren.io.ome_zarr_io import open_multiscale

    client = local_client(workers)
    try:
        image = open_multiscale(path)
        cluster = ClusterRenderer(client, ZarrSpec(str(path), 0, memory), renderer, CHUNK)
        times, shares = [], []
        try:
            for _ in range(frames):
                start = time.perf_counter()
                _, frame = cluster.render(
                    scale_settings(renderer), scale_tf(), scale_camera(image), size, size
                )
                times.append((time.perf_counter() - start) * 1000.0)
                shares.append(frame.composite_ms / frame.total_ms)
        finally:
            cluster.close()
        return {"ms": times, "composite_share": shares, "runs": frame.runs}
    finally:
        local = client.cluster
        client.close()
        local.close()


@dataclass(frozen=True)
class LayerCosts:
    """Measured: `over` per pixel (s), moving a layer between processes per byte (s), latency (s)."""

    over_s_per_pixel: float
    transfer_s_per_byte: float
    latency_s: float


def _echo(layer):
    return layer


def _nothing():
    return None


def layer_costs(size: int, repeats: int = 5) -> LayerCosts:
    """The three costs, measured here: `over` on size^2 layers; a size^2 float32 RGBA layer sent
    to a worker and back (two moves); an empty task's round trip."""
    from volren.bricked.cluster import local_client
    from volren.bricked.composite import over

    rng = np.random.default_rng(1)
    front = rng.random((size, size, 4), dtype=np.float32) * 0.5
    back = rng.random((size, size, 4), dtype=np.float32) * 0.5
    out = np.empty_like(front)
    over_times = []
    for _ in range(repeats):
        start = time.perf_counter()
        over(front, back, out=out)
        over_times.append(time.perf_counter() - start)
    client = local_client(1)
    try:
        client.submit(_nothing, pure=False).result()
        trips, moves = [], []
        for _ in range(repeats):
            start = time.perf_counter()
            client.submit(_nothing, pure=False).result()
            trips.append(time.perf_counter() - start)
            start = time.perf_counter()
            client.submit(_echo, front, pure=False).result()
            moves.append(time.perf_counter() - start)
    finally:
        local = client.cluster
        client.close()
        local.close()
    latency = statistics.median(trips)
    transfer = max(statistics.median(moves) - latency, 0.0) / (2 * front.nbytes)
    return LayerCosts(statistics.median(over_times) / (size * size), transfer, latency)


def composite_model(costs: LayerCosts, pixels: int, workers: int) -> dict[str, float]:
    """Seconds to composite `workers` full-frame layers of `pixels` RGBA float32 pixels:
    - gather: every layer to one node, which composites them in order;
    - binary swap: log2 P rounds, each node sends and composites half its current region, then
      the 1/P pieces are gathered;
    - radix-k (k = 4, as IceT defaults to 4-8): log_k P rounds, each node exchanging (k-1)/k of its
      region with k-1 partners at once, then the gather of pieces.
    Nodes work in parallel, and the messages a node receives in one round overlap (one latency
    per round); a node's bytes and composites add up."""
    per_pixel = 16 * costs.transfer_s_per_byte + costs.over_s_per_pixel
    p = workers
    # messages a node receives at once overlap: one latency per round, bandwidth for every byte
    gather = costs.latency_s + (p - 1) * pixels * per_pixel
    final_gather = costs.latency_s + pixels * (1 - 1 / p) * 16 * costs.transfer_s_per_byte
    swap = math.log2(p) * costs.latency_s + pixels * (1 - 1 / p) * per_pixel + final_gather
    radix = math.log(p, 4) * costs.latency_s + pixels * (1 - 1 / p) * per_pixel + final_gather
    return {"gather": gather, "binary_swap": swap, "radix_k": radix}


def run_scale(sizes: list[int], image: int, memory: int, frames: int, cluster_size: int, renderer: str,
              data: Path, out: Path) -> int:  # fmt: skip
    from volren.bricked.zarr_source import level_for_view
    from volren.io.ome_zarr_io import human_size, open_multiscale

    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for n in sizes:
        path = ensure_volume(data, n)
        multiscale = open_multiscale(path)
        lod = level_for_view(multiscale.levels, scale_camera(multiscale), image, image)
        full_frames = frames if n <= 1024 else 1  # a full-resolution 2048^3 frame takes minutes here
        for level in sorted({0, lod}):
            result = probe(path, level, memory, image, full_frames if level == 0 else frames, renderer)
            timed = result["ms"][1:] or result["ms"]
            row = {"size": n, "level": level, "lod": level == lod, "ms": statistics.median(timed),
                   "frames": len(timed), "peak_rss": result["peak_rss"], "cache_peak": result["cache_peak"],
                   "bricks": result["bricks"], "drawn": result["drawn"]}  # fmt: skip
            rows.append(row)
            print(
                f"scale {n}^3 level {level}{' (LoD)' if level == lod else ''}: {row['ms'] / 1000:.1f} s a frame, "
                f"peak memory {human_size(row['peak_rss'])}, {row['drawn']} of {row['bricks']} bricks",
                flush=True,
            )
    path = ensure_volume(data, cluster_size)
    cluster = {}
    for workers in (1, 2):
        result = cluster_frames(path, workers, image, frames, renderer, memory)
        timed = result["ms"][1:] or result["ms"]
        cluster[workers] = {"ms": statistics.median(timed), "composite_share": statistics.median(result["composite_share"][1:] or result["composite_share"]),
                            "runs": result["runs"]}  # fmt: skip
        print(
            f"scale cluster of {workers}: {cluster[workers]['ms'] / 1000:.2f} s a frame, final composite "
            f"{100 * cluster[workers]['composite_share']:.1f} %",
            flush=True,
        )
    costs = layer_costs(image)
    model = {p: composite_model(costs, image * image, p) for p in (8, 16, 64, 256, 1024)}
    data_out = {"sizes": rows, "cluster": cluster, "cluster_size": cluster_size, "image": image, "memory": memory,
                "renderer": renderer, "layer_costs": costs.__dict__, "model": model}  # fmt: skip
    (out / "scale.json").write_text(json.dumps(data_out, indent=1))
    (out / "scale.md").write_text(scale_markdown(data_out))
    print(f"wrote {out / 'scale.md'}")
    return 0


def scale_markdown(d: dict) -> str:
    from volren.io.ome_zarr_io import human_size

    image, memory = d["image"], d["memory"]
    lines = [
        f"`{COMMAND}` ({d['renderer']}, {image}x{image}, --memory {human_size(memory)}; procedural "
        "Marschner-Lobb in a sphere, uint16, OME-Zarr of 64^3 bricks; each row a fresh process streaming brick by "
        "brick, median of the frames after the first (one frame for full-resolution 2048^3)).",
        "",
        "| volume | level | frame | peak resident memory | chunk cache peak | bricks drawn |",
        "|---|---|---|---|---|---|",
    ]
    for r in d["sizes"]:
        level = f"{r['level']}" + (" (level of detail)" if r["lod"] else "")
        lines.append(
            f"| {r['size']}^3 ({human_size(r['size'] ** 3 * 2)}) | {level} | {r['ms'] / 1000:.2f} s | "
            f"{human_size(r['peak_rss'])} | {human_size(r['cache_peak'])} | {r['drawn']} of {r['bricks']} |"
        )
    cluster = {int(k): v for k, v in d["cluster"].items()}
    c1, c2 = cluster[1], cluster[2]
    lines += [
        "",
        f"LocalCluster, {d['cluster_size']}^3 level 0 (it fits), one thread per worker: 1 worker "
        f"{c1['ms'] / 1000:.2f} s a frame, 2 workers {c2['ms'] / 1000:.2f} s: **{c1['ms'] / c2['ms']:.2f}x** the frames "
        f"per second (goal 1.6x). The client's final composite takes {100 * c1['composite_share']:.1f} % and "
        f"{100 * c2['composite_share']:.1f} % of the frame (goal at most 15 %).",
        "",
        f"Compositing model (measured here: `over` {d['layer_costs']['over_s_per_pixel'] * 1e9:.1f} ns a pixel, "
        f"moving a layer {d['layer_costs']['transfer_s_per_byte'] * 1e9:.2f} ns a byte, a message "
        f"{d['layer_costs']['latency_s'] * 1000:.1f} ms, a dask task's round trip), seconds to composite one {image}x{image} frame from P "
        "full-frame layers:",
        "",
        "| workers P | gather | binary swap | radix-k (k = 4) |",
        "|---|---|---|---|",
    ]
    for p, m in d["model"].items():
        lines.append(f"| {p} | {m['gather']:.3f} | {m['binary_swap']:.3f} | {m['radix_k']:.3f} |")
    lines += [
        "",
        "Gather grows with P; binary swap and radix-k stay near one frame's worth of sends and composites "
        "plus their rounds' latencies, radix-k with fewer rounds. Layers here are cropped to each run's pixels, "
        "so the measured composites are smaller than the model's full-frame layers.",
    ]
    return "\n".join(lines) + "\n"


def run_scale_args(args: argparse.Namespace) -> int:
    from volren.io.ome_zarr_io import parse_memory

    try:
        sizes = [int(v) for v in args.sizes.split(",") if v]
    except ValueError:
        raise VolrenError(f"--sizes takes numbers like 256,512, got {args.sizes!r}") from None
    for n in [*sizes, args.cluster_size]:
        if not 16 <= n <= 4096:
            raise VolrenError(f"--sizes and --cluster-size take sides from 16 to 4096, got {n}")
    if not 16 <= args.image <= 8192 or args.frames < 1:
        raise VolrenError("--image takes 16..8192 pixels and --frames at least 1")
    return run_scale(sizes, args.image, parse_memory(args.memory), args.frames, args.cluster_size, args.renderer,
                     Path(args.data), Path(args.out))  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    s = argparse.ArgumentParser(prog=COMMAND, description="time and peak memory against volume size, out of core "
                                "and on a LocalCluster")  # fmt: skip
    s.add_argument(
        "--sizes", default="256,512,1024,2048", help="volume sides n (n^3 uint16; default 256,512,1024,2048)"
    )
    s.add_argument("--image", type=int, default=1024, help="image side in pixels (default 1024)")
    s.add_argument("--memory", default="2GB", help="chunk cache budget of each process (default 2GB)")
    s.add_argument(
        "--frames", type=int, default=3, help="frames per measurement; the first is not counted (default 3)"
    )
    s.add_argument(
        "--cluster-size", type=int, default=512, help="volume side for the 1- and 2-worker runs (default 512)"
    )
    s.add_argument("--renderer", default="slicer", help="a renderer that draws bricks (default slicer)")
    s.add_argument(
        "--data",
        default="bench-data",
        help="folder for the generated OME-Zarr volumes (kept; default bench-data)",
    )
    s.add_argument(
        "--out", default="docs/bench", help="folder for scale.md and scale.json (default docs/bench)"
    )
    return run(run_scale_args, s, argv)


if __name__ == "__main__":
    sys.exit(main())
