"""`python -m benchmarks.give_up_times`: how long volren takes to give up on a server that does
not answer, against the time limit it was given.

Why: an OME-Zarr URL on a silent HTTP server and a --scheduler address where nothing speaks
dask must each end in a one-line error after about their limit, not hang. The tests check the
errors and that the limits reach the clients; how long the wait really is depends on the machine
and its load, so it is measured here: for each case, the limit and the median seconds from the
call to the error over `--repeats` tries.

    .venv/bin/python -m benchmarks.give_up_times
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable

from volren.errors import VolrenError


def seconds_to_error(action: Callable[[], object]) -> float:
    """Seconds from calling `action` to its VolrenError (it must raise one)."""
    start = time.perf_counter()
    try:
        action()
    except VolrenError:
        return time.perf_counter() - start
    raise AssertionError("expected a VolrenError")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--limit", type=float, default=1.0, help="the time limit given, seconds")
    args = parser.parse_args()

    from volren.bricked.cluster import connect
    from volren.io import load_volume, ome_zarr_io
    from volren.testing.silent_server import silent_server

    ome_zarr_io.URL_TIMEOUT_S = args.limit
    cases = {
        "OME-Zarr URL, silent HTTP server": lambda port: load_volume(f"http://127.0.0.1:{port}/image.zarr"),
        "dask scheduler, silent port": lambda port: connect(f"tcp://127.0.0.1:{port}", timeout=args.limit),
        "dask scheduler, closed port": lambda port: connect("tcp://127.0.0.1:9", timeout=args.limit),
    }
    print(f"{'case':<36} {'limit s':>8} {'median s':>9} {'max s':>7}")
    for name, action in cases.items():
        times = []
        for _ in range(args.repeats):
            with silent_server() as port:
                times.append(seconds_to_error(lambda: action(port)))  # noqa: B023 - called at once
        print(f"{name:<36} {args.limit:>8.2f} {statistics.median(times):>9.2f} {max(times):>7.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
