"""One process's frames of an OME-Zarr level, streamed brick by brick, for `python -m benchmarks.scale`:
run as its own process so that its peak resident memory is the frame's alone.

    python -m benchmarks.scale_probe PATH LEVEL MEMORY SIZE FRAMES RENDERER

prints one JSON line: each frame's ms, the peak resident memory (bytes), the chunk cache's peak,
and the last frame's counters.
"""

from __future__ import annotations

import json
import resource
import sys
import time

from benchmarks.scale_scene import scale_camera, scale_settings, scale_tf


def main(argv: list[str]) -> int:
    from volren.bricked.sort_last import render_bricked
    from volren.bricked.zarr_source import ZarrSource
    from volren.io.ome_zarr_io import open_multiscale
    from volren.renderers.registry import registry

    path, level, memory, size, frames, renderer_name = argv
    level, memory, size, frames = int(level), int(memory), int(size), int(frames)
    image = open_multiscale(path)
    source = ZarrSource(image, level, memory)
    renderer = registry.create(renderer_name)
    renderer.set_settings(scale_settings(renderer_name))
    tf = scale_tf()
    camera = scale_camera(image)
    times, frame = [], None
    for _ in range(frames):
        start = time.perf_counter()
        _, frame = render_bricked(renderer, source, tf, camera, size, size, source.brick)
        times.append((time.perf_counter() - start) * 1000.0)
    renderer.release()
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # kilobytes on Linux
    print(json.dumps({"ms": times, "peak_rss": peak, "cache_peak": source.cache.stats.peak_bytes,
                      "bricks": frame.bricks, "drawn": frame.drawn, "read_ms": frame.read_ms,
                      "render_ms": frame.render_ms, "composite_ms": frame.composite_ms}))  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
