"""`python -m benchmarks.preint`: time and accuracy of the pre-integration tables (Lum, Wilson and Ma 2004's Table 1).

For each table size n: seconds for the brute-force O(n^3) table (only where the previous size
predicts it finishes within the limit), the exact O(n^2) table (incremental subrange
integration), Engel's approximate integral-function table, the 3D table for 64 lengths and the
lighting tables (front and back weighted), all
with n_t = n (no oversampling, as in Lum, Wilson and Ma 2004's Table 1), each
the median of several runs, and each one's max error over random entries against the continuous
integral (`volren.renderers.reference.segment_rgba`, float64, adaptive). A second table gives that error for the exact table
as a function of n and n_t (oversampling). Also the time of a repeated (cached) request.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TypeVar

import numpy as np
from numpy.typing import NDArray

from benchmarks._cli import int_list, run
from volren.bench.datasets import shared_folder
from volren.errors import VolrenError
from volren.model.preintegration import (
    LengthAxis,
    TableCache,
    lighting_tables,
    preintegrate,
    preintegrate_approximate,
    preintegrate_brute_force,
)
from volren.model.preintegration.tables import MAX_TABLE_BYTES
from volren.model.transfer_function import TransferFunction1D
from volren.renderers.reference import segment_rgba
from volren.samples import sample_paths

T = TypeVar("T")

DEFAULT_SIZES = (32, 64, 128, 256, 512, 1024, 2048, 4096)
DEFAULT_OVERSAMPLING = (1, 2, 4, 8)
DEFAULT_ERROR_SIZES = (64, 256, 1024)
#: 3D tables above this size are not timed (n = 2048 with 64 lengths would be 4 GiB).
BENCH_3D_BYTES = 1 << 30


@dataclass
class SizeRow:
    """One line of the main table; None where a column was not measured."""

    n: int
    brute_s: float | None = None
    exact_s: float = 0.0
    approx_s: float = 0.0
    table3d_s: float | None = None
    lighting_s: float = 0.0
    cached_ms: float = 0.0
    errors: dict[str, float | None] = field(default_factory=dict)


def median_seconds(work: Callable[[], T], repeats: int) -> tuple[float, T]:
    """Median wall time of `repeats` runs after one warm-up run (compilation, first-touch
    memory), and the result of the last run (so the measured table need not be built again)."""
    result = work()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        result = work()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def sample_entries(n: int, count: int, rng: np.random.Generator) -> NDArray[np.int64]:
    """(count, 2) random (front, back) indices, a tenth of them on or next to the diagonal."""
    idx = rng.integers(0, n, size=(count, 2))
    near = max(1, count // 10)
    idx[:near, 1] = np.clip(idx[:near, 0] + rng.integers(-1, 2, size=near), 0, n - 1)
    return idx


def values_of(idx: NDArray, n: int, lo: float, hi: float) -> NDArray[np.float64]:
    return lo + (hi - lo) * (idx / (n - 1))


def max_error(table: NDArray, idx: NDArray, truth: NDArray) -> float:
    return float(np.abs(table[idx[:, 0], idx[:, 1]].astype(np.float64) - truth).max())


def measure_size(
    tf: TransferFunction1D,
    n: int,
    step: float,
    lengths: int,
    entries: int,
    repeats: int,
    run_brute: bool,
    rng: np.random.Generator,
) -> SizeRow:
    lo, hi = tf.value_range
    row = SizeRow(n)
    idx = sample_entries(n, entries, rng)
    values = values_of(idx, n, lo, hi)
    truth = segment_rgba(tf, values[:, 0], values[:, 1], step)

    row.exact_s, exact = median_seconds(
        lambda: preintegrate(tf, n, step, oversampling=1, cache=None), repeats
    )
    row.errors["exact"] = max_error(exact, idx, truth)
    row.lighting_s, _ = median_seconds(
        lambda: lighting_tables(tf, n, step, oversampling=1, cache=None), repeats
    )
    row.approx_s, approx = median_seconds(
        lambda: preintegrate_approximate(tf, n, step, oversampling=1), repeats
    )
    row.errors["approximate"] = max_error(approx, idx, truth)
    if run_brute:
        start = time.perf_counter()
        brute = preintegrate_brute_force(tf, n, step, oversampling=1)
        row.brute_s = time.perf_counter() - start
        row.errors["brute"] = max_error(brute, idx, truth)  # type: ignore[arg-type]
        row.errors["exact_vs_brute"] = float(np.abs(exact.astype(np.float64) - brute).max())  # type: ignore[union-attr]

    axis = LengthAxis(max_length=4 * step, count=lengths)
    if lengths * n * n * 16 <= min(BENCH_3D_BYTES, MAX_TABLE_BYTES):
        layers = axis.lengths
        row.table3d_s, table3d = median_seconds(
            lambda: preintegrate(tf, n, lengths=layers, oversampling=1, cache=None), max(1, repeats // 2)
        )
        pick = rng.integers(0, lengths, size=len(idx))
        truth3d = np.stack(
            [
                segment_rgba(tf, values[k : k + 1, 0], values[k : k + 1, 1], layers[pick[k]])[0]
                for k in range(len(idx))
            ]
        )
        got = table3d[pick, idx[:, 0], idx[:, 1]].astype(np.float64)
        row.errors["3d"] = float(np.abs(got - truth3d).max())

    cache = TableCache()
    preintegrate(tf, n, step, oversampling=1, cache=cache)
    start = time.perf_counter()
    preintegrate(tf, n, step, oversampling=1, cache=cache)
    row.cached_ms = (time.perf_counter() - start) * 1e3
    return row


def size_rows(
    tf: TransferFunction1D,
    sizes: Sequence[int],
    step: float,
    lengths: int,
    entries: int,
    repeats: int,
    brute_limit_s: float,
    seed: int = 0,
) -> Iterator[SizeRow]:
    """Rows of the main table, one size at a time (so a caller can show progress)."""
    rng = np.random.default_rng(seed)
    preintegrate_brute_force(tf, 3, step, oversampling=1)  # compile outside the timed run
    last_brute: tuple[int, float] | None = None
    for n in sizes:
        predicted = 0.0 if last_brute is None else last_brute[1] * (n / last_brute[0]) ** 3
        row = measure_size(tf, n, step, lengths, entries, repeats, predicted <= brute_limit_s, rng)
        if row.brute_s is not None:
            last_brute = (n, row.brute_s)
        yield row


def oversampling_errors(
    tf: TransferFunction1D,
    sizes: Sequence[int],
    factors: Sequence[int],
    step: float,
    entries: int,
    seed: int = 1,
) -> dict[tuple[int, int], float]:
    """Max error of the exact table against the continuous integral per (n, oversampling)."""
    rng = np.random.default_rng(seed)
    lo, hi = tf.value_range
    out = {}
    for n in sizes:
        idx = sample_entries(n, entries, rng)
        values = values_of(idx, n, lo, hi)
        truth = segment_rgba(tf, values[:, 0], values[:, 1], step)
        for m in factors:
            out[(n, m)] = max_error(preintegrate(tf, n, step, oversampling=m, cache=None), idx, truth)
    return out


def _fmt_s(value: float | None) -> str:
    if value is None:
        return "-"
    return f"{value * 1e3:.2f} ms" if value < 1 else f"{value:.2f} s"


def _fmt_e(value: float | None) -> str:
    return "-" if value is None else f"{value:.1e}"


def format_size_table(rows: Sequence[SizeRow], lengths: int) -> str:
    head = (
        f"| n | brute force O(n^3) | exact O(n^2) | approximate | 3D, {lengths} lengths | lighting | cached request "
        "| max err exact | max err approx. | max err 3D | max err brute | max exact - brute |"
    )
    lines = [head, "|" + "---|" * 12]
    for r in rows:
        e = r.errors
        lines.append(
            f"| {r.n} | {_fmt_s(r.brute_s)} | {_fmt_s(r.exact_s)} | {_fmt_s(r.approx_s)} | {_fmt_s(r.table3d_s)} "
            f"| {_fmt_s(r.lighting_s)} "
            f"| {r.cached_ms:.3f} ms | {_fmt_e(e.get('exact'))} | {_fmt_e(e.get('approximate'))} "
            f"| {_fmt_e(e.get('3d'))} | {_fmt_e(e.get('brute'))} | {_fmt_e(e.get('exact_vs_brute'))} |"
        )
    return "\n".join(lines)


def format_oversampling_table(errors: dict[tuple[int, int], float]) -> str:
    sizes = sorted({n for n, _ in errors})
    factors = sorted({m for _, m in errors})
    lines = [
        "| n \\ n_t | " + " | ".join(f"n_t = {m}(n-1)+1" for m in factors) + " |",
        "|" + "---|" * (len(factors) + 1),
    ]
    for n in sizes:
        lines.append(f"| {n} | " + " | ".join(_fmt_e(errors[(n, m)]) for m in factors) + " |")
    return "\n".join(lines)


def default_tf_path() -> Path:
    """The engine's spiky TF from the shared scenes when $VOLREN_SHARED names them (two opacity
    spikes narrower than the bins of small tables), else the bundled Marschner-Lobb sample's TF."""
    shared = shared_folder(None, required=False)
    if shared is not None and (shared / "scenes" / "engine-spiky.json").is_file():
        return shared / "scenes" / "engine-spiky.json"
    return sample_paths("marschner_lobb")[1]


def run_tables(args: argparse.Namespace) -> int:
    import numba
    from tqdm import tqdm

    from volren import io

    for name in ("step", "lengths", "entries", "repeats"):
        value = getattr(args, name)
        if not (value > 0 and math.isfinite(value)):
            raise VolrenError(f"--{name} must be positive and finite, got {value}")
    tf_path = Path(args.tf) if args.tf else default_tf_path()
    tf = io.load_transfer_function(tf_path)
    sizes = args.sizes or list(DEFAULT_SIZES)
    rows = []
    with tqdm(total=len(sizes), desc="table sizes", leave=False) as bar:
        for row in size_rows(
            tf, sizes, args.step, args.lengths, args.entries, args.repeats, args.brute_limit
        ):
            rows.append(row)
            bar.set_postfix_str(f"n={row.n}")
            bar.update()
    errors = oversampling_errors(
        tf,
        args.error_sizes or list(DEFAULT_ERROR_SIZES),
        args.oversampling or list(DEFAULT_OVERSAMPLING),
        args.step,
        args.entries,
    )
    lo, hi = tf.value_range
    text = "\n\n".join(
        [
            f"Pre-integration tables for {tf_path.name} over [{lo:g}, {hi:g}], segment length {args.step:g}, "
            f"{numba.get_num_threads()} threads; times are medians of {args.repeats} runs after a warm-up "
            f"(brute force: one run); errors are max abs over {args.entries} random entries (RGBA) against "
            "the continuous integral.",
            format_size_table(rows, args.lengths),
            "Max error of the exact table against the continuous integral by table size n and TF bins n_t - 1:",
            format_oversampling_table(errors),
        ]
    )
    print(text)
    if args.out:
        try:
            Path(args.out).write_text(text + "\n")
        except OSError as exc:
            raise VolrenError(f"{args.out}: cannot write: {exc.strerror or exc}") from None
    return 0


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m benchmarks.preint",
        description="pre-integration tables: seconds and max error per table size",
    )
    p.add_argument(
        "--tf",
        help="transfer-function JSON (default: engine-spiky.json of $VOLREN_SHARED, else the Marschner-Lobb sample TF)",
    )
    p.add_argument("--sizes", type=int_list(2), default=None, help="table sizes n (default 32,64,...,4096)")
    p.add_argument("--step", type=float, default=0.5, help="segment length in world units (default 0.5)")
    p.add_argument("--lengths", type=int, default=64, help="lengths of the 3D table (default 64)")
    p.add_argument("--entries", type=int, default=500, help="random entries checked per size (default 500)")
    p.add_argument("--repeats", type=int, default=5, help="timed runs per table, median reported (default 5)")
    p.add_argument(
        "--brute-limit", type=float, default=60.0, help="skip brute force predicted above this many s"
    )
    p.add_argument(
        "--oversampling", type=int_list(1), default=None, help="n_t factors for the error table (1,2,4,8)"
    )
    p.add_argument(
        "--error-sizes", type=int_list(2), default=None, help="sizes for the error table (64,256,1024)"
    )
    p.add_argument("--out", help="also write the tables to this Markdown file")
    return run(run_tables, p, argv)


if __name__ == "__main__":
    sys.exit(main())
