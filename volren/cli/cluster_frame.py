"""`volren render --cluster local[:N]` and `--scheduler ADDRESS`: the frame drawn sort-last on a
dask.distributed cluster (`volren.bricked.cluster`), brick by brick, equal to one process's."""

from __future__ import annotations

import argparse
from typing import Any

from volren.errors import VolrenError
from volren.model.scene import Scene

#: Render bricks of this many cells per side for an in-memory volume (OME-Zarr: its chunk side).
VOLUME_BRICK = 64


def add_cluster_arguments(p: argparse.ArgumentParser) -> None:
    group = p.add_argument_group("rendering on a dask.distributed cluster (sort-last, brick by brick)")
    where = group.add_mutually_exclusive_group()
    where.add_argument("--cluster", metavar="local[:N]",
                       help="start a LocalCluster of N worker processes, one thread each (default: one per core)")
    where.add_argument("--scheduler", metavar="ADDRESS", help="use the running cluster at ADDRESS, e.g. tcp://host:8786")


def wants_cluster(args: argparse.Namespace) -> bool:
    return bool(getattr(args, "cluster", None) or getattr(args, "scheduler", None))


def cluster_frame(args: argparse.Namespace, scene: Scene, camera, progress) -> tuple[Any, Any, str]:
    """The frame on the cluster the flags name: (image, FrameStats, what was drawn, for the line)."""
    from volren.bricked.cluster import (
        ClusterRenderer,
        VolumeSpec,
        ZarrSpec,
        connect,
        local_client,
        parse_cluster,
    )
    from volren.bricked.zarr_source import level_for_view
    from volren.model.volume import UniformVolume
    from volren.renderers.base import FrameStats

    width, height = scene.size
    zarr_input = getattr(args, "zarr_input", None)
    if zarr_input is not None:
        level = args.level if args.level is not None else level_for_view(zarr_input.image.levels, camera, width, height)
        spec: Any = ZarrSpec(zarr_input.path, level, zarr_input.budget)
        brick = int(min(zarr_input.image.levels[level].chunks))
        what = f"{zarr_input.name} level {level}"
    elif isinstance(scene.volume, UniformVolume):
        spec, brick, what = VolumeSpec(scene.volume), VOLUME_BRICK, scene.volume.name
    else:
        raise VolrenError("--cluster and --scheduler render uniform volumes (bricks); this one is tetrahedral")
    client = connect(args.scheduler) if args.scheduler else local_client(parse_cluster(args.cluster))
    renderer = None
    try:
        renderer = ClusterRenderer(client, spec, scene.renderer, brick)
        image, frame = renderer.render(scene.settings, scene.transfer_function, camera, width, height, progress)
    finally:
        if renderer is not None:
            renderer.close()
        cluster = getattr(client, "cluster", None) if not args.scheduler else None
        client.close()
        if cluster is not None:
            cluster.close()
    counters = {"bricks": frame.bricks, "bricks_drawn": frame.drawn, "bricks_transparent": frame.transparent,
                "runs": frame.runs, "workers": frame.workers, "composite_ms": frame.composite_ms}  # fmt: skip
    note = f" ({what} on {frame.workers} worker{'s' if frame.workers != 1 else ''}: {frame.drawn} of {frame.bricks} " \
           f"bricks drawn in {frame.runs} runs)"  # fmt: skip
    return image, FrameStats(frame.total_ms, width, height, counters), note
