"""`volren bench ...`: benchmarks that print numbers (medians of several runs), never pass/fail.

`volren bench preint` measures the pre-integration tables (`volren.bench.preint`); `volren bench
slicer` times `slicer` and `vtk` against `reference` on the shared scenes (`volren.bench.slicer_table`).
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
    s = kinds.add_parser("slicer", help="slicer and vtk: ms per frame and RMSE against reference per step")
    s.add_argument("--shared", help="the shared folder with data/ and scenes/ (default: ../shared beside the repo)")
    s.add_argument("--datasets", default="bonsai,engine", help="comma-separated (default bonsai,engine)")
    s.add_argument("--styles", default="smooth,spiky,opaque", help="TF styles (default smooth,spiky,opaque)")
    s.add_argument("--steps", default="1,0.5,0.25", help="sample steps (default 1,0.5,0.25)")
    s.add_argument("--paths", default="march", help="slicer paths: march, slices or both (default march)")
    s.add_argument("--size", type=int, default=512, help="image side in pixels (default 512)")
    s.add_argument("--frames", type=int, default=5, help="timed frames per setting, median reported (default 5)")
    s.add_argument("--out", help="also write the table to this Markdown file")
    s.set_defaults(run=run_slicer)


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


def _float_list(text: str, what: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise VolrenError(f"{what} must be comma-separated numbers, got {text!r}") from None
    if not values or not all(v > 0 and math.isfinite(v) for v in values):
        raise VolrenError(f"{what} must be positive finite numbers, got {text!r}")
    return values


def run_slicer(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from volren.bench import slicer_table
    from volren.bench.vtk_vs_reference import SCENES

    shared = Path(args.shared) if args.shared else Path(__file__).resolve().parents[2].parent / "shared"
    if not (shared / "data").is_dir() or not (shared / "scenes").is_dir():
        raise VolrenError(f"{shared}: no data/ and scenes/ folders there (give --shared)")
    datasets = [d for d in args.datasets.split(",") if d]
    unknown = [d for d in datasets if d not in SCENES or SCENES[d][0].startswith("tets/")]
    if unknown:
        grids = ", ".join(n for n, s in SCENES.items() if not s[0].startswith("tets/"))
        raise VolrenError(f"unknown or non-uniform datasets {unknown}; choose from {grids}")
    steps = _float_list(args.steps, "--steps")
    paths = [p for p in args.paths.split(",") if p]
    if not paths or any(p not in ("march", "slices") for p in paths):
        raise VolrenError(f"--paths must name march and/or slices, got {args.paths!r}")
    if args.size < 8 or args.frames < 1:
        raise VolrenError("--size must be at least 8 and --frames at least 1")
    styles = [s for s in args.styles.split(",") if s]
    total = len(datasets) * len(styles) * len(slicer_table.configs(steps, paths))
    lines = [slicer_table.HEADER]
    print(slicer_table.HEADER)
    with tqdm(total=total, desc="settings", leave=False) as bar:

        def report(row: dict) -> None:
            line = slicer_table.markdown_row(row)
            lines.append(line)
            tqdm.write(line)
            bar.update()

        rows = slicer_table.run(shared, datasets, styles, steps, paths, args.size, args.frames, report)
    ratios = [slicer_table.RATIO_HEADER, *slicer_table.equal_error_rows(rows)]
    lines += ["", *ratios]
    print("\n" + "\n".join(ratios))
    if args.out:
        try:
            Path(args.out).write_text("\n".join(lines) + "\n")
        except OSError as exc:
            raise VolrenError(f"{args.out}: cannot write: {exc.strerror or exc}") from None
    return 0
