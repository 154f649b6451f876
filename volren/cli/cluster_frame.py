"""`volren render --cluster local[:N]` and `--scheduler ADDRESS`: the frame drawn sort-last on a
dask.distributed cluster (`volren.bricked.cluster`), brick by brick, equal to one process's."""

from __future__ import annotations

import argparse
from typing import Any

from volren.model.scene import Scene


def add_cluster_arguments(p: argparse.ArgumentParser) -> None:
    group = p.add_argument_group("rendering on a dask.distributed cluster (sort-last, brick by brick)")
    where = group.add_mutually_exclusive_group()
    where.add_argument("--cluster", metavar="local[:N]",
                       help="start a LocalCluster of N worker processes, one thread each (default: one per core)")
    where.add_argument("--scheduler", metavar="ADDRESS", help="use the running cluster at ADDRESS, e.g. tcp://host:8786")


def wants_cluster(args: argparse.Namespace) -> bool:
    """Whether --cluster or --scheduler was given, even empty (refused then, not ignored)."""
    return getattr(args, "cluster", None) is not None or getattr(args, "scheduler", None) is not None


def check_cluster_flag(args: argparse.Namespace) -> None:
    """A --cluster value that names no cluster, refused before the input is read (which can take
    minutes) rather than after."""
    if getattr(args, "cluster", None) is not None:
        from volren.bricked.cluster import parse_cluster

        parse_cluster(args.cluster)


def cluster_frame(args: argparse.Namespace, scene: Scene, camera, progress, quality: str) -> tuple[Any, Any, str]:
    """The frame on the cluster the flags name, at the quality level asked (which picks an OME-Zarr
    input's pyramid level): (image, FrameStats, what was drawn, for the line)."""
    from volren.bricked.cluster import render_on_cluster
    from volren.renderers.base import FrameStats

    width, height = scene.size
    zarr_input = getattr(args, "zarr_input", None)
    image, frame, what = render_on_cluster(args.cluster, args.scheduler, zarr_input or scene.volume, scene.renderer,
                                           scene.settings, scene.transfer_function, camera, width, height, args.level,
                                           progress, quality)  # fmt: skip
    counters = {"bricks": frame.bricks, "bricks_drawn": frame.drawn, "bricks_transparent": frame.transparent,
                "runs": frame.runs, "workers": frame.workers, "composite_ms": frame.composite_ms}  # fmt: skip
    note = f" ({what} on {frame.workers} worker{'s' if frame.workers != 1 else ''}: {frame.drawn} of {frame.bricks} " \
           f"bricks drawn in {frame.runs} runs)"  # fmt: skip
    return image, FrameStats(frame.total_ms, width, height, counters), note
