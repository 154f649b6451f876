"""`volren bench ...`: benchmarks that print numbers (medians of several runs), never pass/fail.

`volren bench preint` measures the pre-integration tables (`volren.bench.preint`).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from volren.errors import VolrenError


def _int_list(minimum: int):
    """argparse type: comma-separated whole numbers >= minimum."""

    def parse(text: str) -> list[int]:
        try:
            values = [int(v) for v in text.split(",") if v.strip()]
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected comma-separated whole numbers, got {text!r}") from None
        if not values or min(values) < minimum:
            raise argparse.ArgumentTypeError(f"expected whole numbers >= {minimum}, got {text!r}")
        return values

    return parse


def add_parser(sub) -> None:
    bench = sub.add_parser("bench", help="benchmarks (print tables of times and errors)")
    kinds = bench.add_subparsers(dest="bench", metavar="BENCHMARK", required=True)
    p = kinds.add_parser("preint", help="pre-integration tables: seconds and max error per table size")
    p.add_argument("--tf", help="transfer-function JSON (default: ../shared/scenes/engine-spiky.json if present)")
    p.add_argument("--sizes", type=_int_list(2), default=None, help="table sizes n (default 32,64,...,4096)")
    p.add_argument("--step", type=float, default=0.5, help="segment length in world units (default 0.5)")
    p.add_argument("--lengths", type=int, default=64, help="lengths of the 3D table (default 64)")
    p.add_argument("--entries", type=int, default=500, help="random entries checked per size (default 500)")
    p.add_argument("--repeats", type=int, default=5, help="timed runs per table, median reported (default 5)")
    p.add_argument("--brute-limit", type=float, default=60.0, help="skip brute force predicted above this many s")
    p.add_argument("--oversampling", type=_int_list(1), default=None, help="n_t factors for the error table (1,2,4,8)")
    p.add_argument("--error-sizes", type=_int_list(2), default=None, help="sizes for the error table (64,256,1024)")
    p.add_argument("--out", help="also write the tables to this Markdown file")
    p.set_defaults(run=run_preint)


def run_preint(args: argparse.Namespace) -> int:
    import numba
    from tqdm import tqdm

    from volren import io
    from volren.bench import preint

    for name in ("step", "lengths", "entries", "repeats"):
        value = getattr(args, name)
        if not (value > 0 and math.isfinite(value)):
            raise VolrenError(f"--{name} must be positive and finite, got {value}")
    tf_path = Path(args.tf) if args.tf else preint.default_tf_path()
    tf = io.load_transfer_function(tf_path)
    sizes = args.sizes or list(preint.DEFAULT_SIZES)
    rows = []
    with tqdm(total=len(sizes), desc="table sizes", leave=False) as bar:
        for row in preint.size_rows(
            tf, sizes, args.step, args.lengths, args.entries, args.repeats, args.brute_limit
        ):
            rows.append(row)
            bar.set_postfix_str(f"n={row.n}")
            bar.update()
    errors = preint.oversampling_errors(
        tf,
        args.error_sizes or list(preint.DEFAULT_ERROR_SIZES),
        args.oversampling or list(preint.DEFAULT_OVERSAMPLING),
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
            preint.format_size_table(rows, args.lengths),
            "Max error of the exact table against the continuous integral by table size n and TF bins n_t - 1:",
            preint.format_oversampling_table(errors),
        ]
    )
    print(text)
    if args.out:
        try:
            Path(args.out).write_text(text + "\n")
        except OSError as exc:
            raise VolrenError(f"{args.out}: cannot write: {exc.strerror or exc}") from None
    return 0
