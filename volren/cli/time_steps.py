"""INPUT as a time series: which volume file `--time-step` names (`volren.io.series_io`)."""

from __future__ import annotations

import argparse

from volren.errors import VolrenError


def input_series(args: argparse.Namespace):
    """The time series INPUT names (None: INPUT is one volume); --time-step refused without one."""
    from volren.io.series_io import is_series, load_series

    if args.input is not None and not args.raw_shape and is_series(args.input):
        return load_series(args.input)
    if args.time_step is not None:
        raise VolrenError(f"--time-step applies to a time series INPUT (a .pvd, or a folder of volume files); "
                          f"{args.input or 'the scene'} is one volume")  # fmt: skip
    return None


def step_path(args: argparse.Namespace) -> str:
    """INPUT itself, or the file of the time step asked for when INPUT is a series."""
    series = input_series(args)
    if series is None:
        return args.input
    step = 0 if args.time_step is None else args.time_step
    if not 0 <= step < len(series):
        raise VolrenError(f"--time-step {step}: {args.input} has steps 0 to {len(series) - 1}")
    return str(series.steps[step])
