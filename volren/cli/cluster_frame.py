"""`volren render --cluster local[:N]` and `--scheduler ADDRESS`: the flags that draw the frame
sort-last on a dask.distributed cluster, brick by brick, equal to one process's (the frame itself:
`volren.draw.frame.draw_on_cluster`)."""

from __future__ import annotations

import argparse


def add_cluster_arguments(p: argparse.ArgumentParser) -> None:
    group = p.add_argument_group("rendering on a dask.distributed cluster (sort-last, brick by brick)")
    where = group.add_mutually_exclusive_group()
    where.add_argument(
        "--cluster",
        metavar="local[:N]",
        help="start a LocalCluster of N worker processes, one thread each (default: one per core)",
    )
    where.add_argument(
        "--scheduler", metavar="ADDRESS", help="use the running cluster at ADDRESS, e.g. tcp://host:8786"
    )


def wants_cluster(args: argparse.Namespace) -> bool:
    """Whether --cluster or --scheduler was given, even empty (refused then, not ignored)."""
    return getattr(args, "cluster", None) is not None or getattr(args, "scheduler", None) is not None


def check_cluster_flag(args: argparse.Namespace) -> None:
    """A --cluster value that names no cluster, refused before the input is read (which can take
    minutes) rather than after."""
    if getattr(args, "cluster", None) is not None:
        from volren.bricked.cluster import parse_cluster

        parse_cluster(args.cluster)
