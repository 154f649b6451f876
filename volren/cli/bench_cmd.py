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


def _shared_path(text: str | None) -> Path:
    """The --shared folder, or ../shared beside the repository."""
    return Path(text) if text else Path(__file__).resolve().parents[2].parent / "shared"


def _has_data(shared: Path) -> bool:
    return (shared / "data").is_dir() and (shared / "scenes").is_dir()


def _shared(text: str | None) -> Path:
    """The shared folder with data/ and scenes/, or a one-line error."""
    shared = _shared_path(text)
    if not _has_data(shared):
        raise VolrenError(f"{shared}: no data/ and scenes/ folders there (give --shared)")
    return shared


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
    add_skip_parser(kinds)
    add_run_parser(kinds)
    add_stress_parser(kinds)
    add_app_parsers(kinds)


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

    shared = _shared(args.shared)
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


def add_skip_parser(kinds) -> None:
    """`bench skip` (issue 7): each skipping technique on and off per renderer (volren.bench.skipping)."""
    k = kinds.add_parser("skip", help="skipping techniques on and off: ms, work counters, image change")
    k.add_argument("--shared", help="the folder with data/ and scenes/ (default: ../shared beside the repo)")
    k.add_argument("--samples", action="store_true", help="the bundled samples instead of ../shared")
    k.add_argument("--datasets", help="comma-separated (default: every shared dataset, or every sample)")
    k.add_argument("--styles", help="TF styles (default smooth,spiky,opaque)")
    k.add_argument("--renderers", default="slicer,tetra,vtk", help="comma-separated (default: all three)")
    k.add_argument("--size", type=int, help="image side in pixels (default 512; 128 with --quick)")
    k.add_argument("--frames", type=int, help="timed frames per row, median (default 5; 3 with --quick)")
    k.add_argument("--turn", type=float, default=1.0, help="azimuth degrees between timed frames (0: fixed)")
    k.add_argument("--step", type=float, default=0.5, help="sample step (default 0.5)")
    k.add_argument("--preintegration", action="store_true", help="pre-integrated classification")
    k.add_argument("--quick", action="store_true", help="128x128, two small scenes (ironProt, spx), 3 frames")
    k.add_argument("--out", help="folder to write skip.csv and skip.md into")
    k.set_defaults(run=run_skip)


def run_skip(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from volren.bench import skipping
    from volren.model.settings import RenderSettings

    size = args.size or (128 if args.quick else 512)
    frames = args.frames or (3 if args.quick else 5)
    finite = math.isfinite(args.turn) and math.isfinite(args.step)
    if size < 8 or frames < 1 or not (finite and args.step > 0):
        raise VolrenError("--size must be at least 8, --frames at least 1, --turn finite and --step positive")
    renderers = [r for r in args.renderers.split(",") if r]
    if not renderers or set(renderers) - set(skipping.RENDERERS):
        names = ", ".join(skipping.RENDERERS)
        raise VolrenError(f"--renderers must name some of {names}, got {args.renderers!r}")
    shared = _shared_path(args.shared)
    kinds, scenes = skipping.plan(shared, args.samples, args.datasets, args.styles, args.quick)
    base = RenderSettings(step=args.step, preintegration=args.preintegration)
    print(skipping.HEADER)
    with tqdm(total=skipping.row_count(kinds, renderers, base), desc="configurations", leave=False) as bar:

        def report(row: dict) -> None:
            tqdm.write(skipping.markdown_row(row))
            bar.update()

        rows = skipping.run(scenes, renderers, size, frames, args.turn, base, report)
    print("\n" + "\n".join([skipping.SUMMARY_HEADER, *skipping.summary_rows(rows)]))
    if args.out:
        command = (
            f"volren bench skip --size {size} --frames {frames} --turn {args.turn:g} --step {args.step:g}"
            f"{' --preintegration' if args.preintegration else ''}{' --samples' if args.samples else ''}"
            f" --renderers {','.join(renderers)}"
        )
        intro = skipping.intro(size, frames, args.turn, base, command)
        try:
            out = Path(args.out)
            out.mkdir(parents=True, exist_ok=True)
            skipping.write_csv(rows, out / "skip.csv")
            (out / "skip.md").write_text(skipping.markdown(rows, intro))
        except OSError as exc:
            raise VolrenError(f"{args.out}: cannot write: {exc.strerror or exc}") from None
    return 0


# --------------------------------------------------------------------------- bench run (issue 7)
def add_run_parser(kinds) -> None:
    r = kinds.add_parser("run", help="every renderer and quality setting: ms against error, CSV, plots")
    r.add_argument("--quick", action="store_true",
                   help="128x128, two bundled samples, 3 frames, a few settings per renderer (for CI)")
    r.add_argument("--out", default="bench-run", help="folder for runs.csv, <dataset>.png, summary.md")
    r.add_argument("--shared", help="the folder with data/ and scenes/ (default: ../shared beside the repo)")
    r.add_argument("--datasets", help="comma-separated (default: every shared dataset and bundled sample)")
    r.add_argument("--tfs", help="TF styles to keep, e.g. smooth,spiky (default: all)")
    r.add_argument("--renderers", help="curves to run, e.g. slicer,vtk-gpu,tetra,vtk-raycast, or any registered "
                   "renderer (a plugin: swept along its declared quality axis) (default: the built-in curves)")
    r.add_argument("--steps", help="the swept sample steps (default 2,1,0.5,0.25; --quick 2,0.5)")
    r.add_argument("--size", type=int, help="image side in pixels (default 512; --quick 128)")
    r.add_argument("--frames", type=int, help="timed frames per setting, median taken (default 5; --quick 3)")
    r.add_argument("--turn", type=float, default=2.0, help="azimuth degrees between timed frames (default 2)")
    r.set_defaults(run=run_run)


def _names(text: str | None) -> list[str] | None:
    return None if text is None else [n for n in text.split(",") if n]


def run_run(args: argparse.Namespace) -> int:
    import time

    from tqdm import tqdm

    from volren.bench import datasets, plots, run_bench, summary, sweep

    plots.require_matplotlib()  # before the sweep, not after it: the plots come last
    size = args.size or (128 if args.quick else 512)
    frames = args.frames or (3 if args.quick else 5)
    if size < 8 or frames < 1 or not (math.isfinite(args.turn) and args.turn >= 0):
        raise VolrenError("--size must be at least 8, --frames at least 1 and --turn finite and >= 0")
    steps = _float_list(args.steps, "--steps") if args.steps else None
    curves = sweep.check_curves(_names(args.renderers)) if args.renderers else None
    shared = _shared(args.shared) if args.shared else _shared_path(None)
    if not _has_data(shared):
        shared = None  # the default folder is absent: bundled samples only
    chosen = datasets.select(_names(args.datasets), shared, args.quick)
    styles = _names(args.tfs)

    def configs(kind: str) -> list:
        return sweep.configs(kind, args.quick, steps, curves)

    total = sum(len(configs(d.kind)) for d in chosen for s, _ in d.tf_paths if styles is None or s in styles)
    out = Path(args.out)
    try:
        out.mkdir(parents=True, exist_ok=True)
        stream = (out / "runs.csv").open("w", newline="")
    except OSError as exc:
        raise VolrenError(f"{out}: cannot write: {exc.strerror or exc}") from None
    start, rows, skipped = time.perf_counter(), [], []
    with stream, tqdm(total=total, desc="bench run", unit="run", leave=False) as bar:

        class BarProgress(run_bench.Progress):
            def status(self, text: str) -> None:
                bar.set_postfix_str(text[:70])

            def row(self, row: dict) -> None:
                bar.update()

            def skipped(self, what: str, reason: str) -> None:
                skipped.append(f"{what}: {reason}")
                tqdm.write(f"skipped {what}: {reason}")
                bar.update()

        writer = run_bench.CsvWriter(stream)
        for row in run_bench.run(chosen, configs, size, frames, args.turn, styles, BarProgress()):
            writer.write(row)
            rows.append(row)
    if not rows:
        raise VolrenError("no configuration ran (see the skipped lines above, or widen --renderers / --tfs)")
    pictures = plots.plot_all(rows, out)
    info = summary.RunInfo(size, frames, args.turn, time.perf_counter() - start, skipped)
    text = summary.markdown(rows, info)
    (out / "summary.md").write_text(text + "\n")
    print(text)
    print(f"\nwrote {out / 'runs.csv'} ({len(rows)} rows), {len(pictures)} plots and {out / 'summary.md'}")
    return 0


# ------------------------------------------------------------------------ bench stress (issue 7)
def add_stress_parser(kinds) -> None:
    """`bench stress`: NaN/Inf/out-of-range pixels and error against reference on extreme input."""
    t = kinds.add_parser("stress", help="numerical stability: NaN/Inf/out-of-range counts on extreme input")
    t.add_argument("--quick", action="store_true", help="a subset of the scenes and tables (well under a minute)")
    t.add_argument("--out", help="folder to write stress.csv and stress.md into (default: write nothing)")
    t.add_argument("--size", type=int, default=64, help="image side in pixels (default 64)")
    t.add_argument("--renderers", help="comma-separated renderers besides reference (default: all registered)")
    t.add_argument("--cases", help="comma-separated globs of scene names, e.g. 'tet-*,*/spike' (default: all)")
    t.add_argument("--suites", default="images,tables", help="images, tables or both (default: both)")
    t.add_argument("--eps", type=float, default=None, help="how far a premultiplied colour may exceed its alpha "
                   "(default 1e-4; 8-bit output rounds by up to 1/255)")
    t.set_defaults(run=run_stress)


def run_stress(args: argparse.Namespace) -> int:
    """Exit status 1 when any image or table holds NaN, Inf or out-of-range values or a run crashed."""
    import sys
    import time

    from tqdm import tqdm

    from volren.bench import stress

    suites = {s for s in args.suites.split(",") if s}
    if not suites or suites - {"images", "tables"}:
        raise VolrenError(f"--suites must name images and/or tables, got {args.suites!r}")
    if not 8 <= args.size <= 4096:
        raise VolrenError(f"--size must lie in 8..4096, got {args.size}")
    eps = stress.COLOR_EPS if args.eps is None else args.eps
    if not (math.isfinite(eps) and eps >= 0):
        raise VolrenError(f"--eps must be finite and >= 0, got {eps}")
    renderers = [r for r in args.renderers.split(",") if r] if args.renderers else None
    patterns = [p for p in args.cases.split(",") if p] if args.cases else None
    start = time.perf_counter()
    work = stress.plan(args.quick, None, renderers, patterns, "images" in suites, "tables" in suites)
    for note in work.notes:
        print(f"note: {note}", file=sys.stderr)
    print(stress.ROW_HEADER)
    with tqdm(total=len(work), desc="stress", unit="run", leave=False) as bar:

        def report(row: stress.Row) -> None:
            tqdm.write(stress.markdown_row(row))
            bar.set_postfix_str(row.case[:40])
            bar.update()

        rows = stress.run(work, None, args.size, eps, report)
    seconds = time.perf_counter() - start
    print("\n" + stress.summary_table(rows))
    if args.out:
        try:
            out = Path(args.out)
            out.mkdir(parents=True, exist_ok=True)
            stress.write_csv(rows, out / "stress.csv")
            (out / "stress.md").write_text(stress.markdown(rows, seconds, args.size, args.quick, work.notes, eps))
        except OSError as exc:
            raise VolrenError(f"{args.out}: cannot write: {exc.strerror or exc}") from None
    bad = stress.problems(rows)
    print(f"\n{len(rows)} runs in {seconds:.0f} s; {len(bad)} with NaN, Inf, out-of-range values or a crash")
    for row in bad:
        what = f"{row.nan} NaN, {row.inf} Inf, {row.out_of_range} out of range"
        what += f" (by up to {row.excess:.2g})" if row.out_of_range else ""
        detail = "; ".join(t for t in (what if row.status == "bad" else "", row.message) if t)
        print(f"problem: {row.case} {row.renderer} ({row.settings}): {row.status}: {detail}", file=sys.stderr)
    return 1 if bad else 0


def add_app_parsers(kinds) -> None:
    """`bench app` (the desktop app's latency and frame rate) and `bench all` (BENCHMARKS.md)."""
    a = kinds.add_parser("app", help="desktop app: TF edit -> new frame latency, frames per second rotating")
    a.add_argument("--shared", help="the folder with data/ and scenes/ (default: ../shared beside the repo)")
    a.add_argument("--datasets", default="ironProt,bonsai", help="comma-separated (default ironProt,bonsai)")
    a.add_argument("--renderers", default="slicer,vtk", help="comma-separated (default slicer,vtk)")
    a.add_argument("--style", default="smooth", help="TF style of the scenes (default smooth)")
    a.add_argument("--edits", type=int, default=7, help="timed TF edits, median reported (default 7)")
    a.add_argument("--seconds", type=float, default=3.0, help="length of each drag gesture (default 3 s)")
    a.add_argument("--histogram-size", type=int, default=256,
                   help="time the 2D TF editor's joint histogram of an N^3 volume (default 256; 0: not)")
    a.add_argument("--out", help="folder to write app.md into")
    a.set_defaults(run=run_app)
    b = kinds.add_parser("all", help="run, skip, stress and app into one folder, then write BENCHMARKS.md")
    b.add_argument("--out", default="docs/bench", help="folder for every result (default docs/bench)")
    b.add_argument("--markdown", default="BENCHMARKS.md", help="the summary file (default BENCHMARKS.md)")
    b.add_argument("--shared", help="the folder with data/ and scenes/ (default: ../shared beside the repo)")
    b.add_argument("--run-args", default="", help="extra arguments for `bench run`, e.g. '--steps 1,0.5'")
    b.add_argument("--only", default="run,skip,stress,app", help="which benchmarks to run (default: all four)")
    b.set_defaults(run=run_all)


def run_app(args: argparse.Namespace) -> int:
    from volren.extras import require

    require("app", "volren bench app")  # before anything is loaded
    from volren.bench import app_latency
    from volren.bench.vtk_vs_reference import SCENES

    shared = _shared(args.shared)
    datasets = [d for d in args.datasets.split(",") if d]
    unknown = [d for d in datasets if d not in SCENES]
    if unknown:
        raise VolrenError(f"unknown datasets {unknown}; choose from {', '.join(SCENES)}")
    if args.edits < 1 or not (math.isfinite(args.seconds) and args.seconds > 0):
        raise VolrenError("--edits must be at least 1 and --seconds positive")
    app = app_latency.application()
    lines = [app_latency.HEADER]
    print(app_latency.HEADER, flush=True)
    for dataset in datasets:
        volume, tf = app_latency.scene_inputs(shared, dataset, args.style)
        for renderer in [r for r in args.renderers.split(",") if r]:
            timing = app_latency.measure(app, volume, tf.copy(), renderer, dataset, args.edits, args.seconds)
            lines.append(app_latency.markdown_row(timing))
            print(lines[-1], flush=True)
    note = app_latency.NOTE.format(
        w=app_latency.VIEWPORT[0], h=app_latency.VIEWPORT[1], style=args.style, platform=app.platformName()
    )
    if args.histogram_size > 0:
        seconds = app_latency.joint_histogram_seconds(args.histogram_size)
        lines += ["", app_latency.histogram_line(args.histogram_size, seconds)]
        print("\n" + lines[-1], flush=True)
    if args.out:
        out = Path(args.out)
        try:
            out.mkdir(parents=True, exist_ok=True)
            (out / "app.md").write_text(note + "\n\n" + "\n".join(lines) + "\n")
        except OSError as exc:
            raise VolrenError(f"{args.out}: cannot write: {exc.strerror or exc}") from None
    return 0


def run_all(args: argparse.Namespace) -> int:
    """Every benchmark into one folder, then BENCHMARKS.md from their fragments (volren.bench.report)."""
    import shlex
    import time

    from volren.bench import report
    from volren.cli.main import main

    out = Path(args.out)
    shared = ["--shared", args.shared] if args.shared else []
    commands = {
        "run": ["bench", "run", "--out", str(out), *shared, *shlex.split(args.run_args)],
        "skip": ["bench", "skip", "--out", str(out), *shared],
        "stress": ["bench", "stress", "--out", str(out)],
        "app": ["bench", "app", "--out", str(out), *shared],
    }
    chosen = [c for c in args.only.split(",") if c]
    unknown = set(chosen) - set(commands)
    if unknown:
        raise VolrenError(f"--only names unknown benchmarks {sorted(unknown)}; choose from {', '.join(commands)}")
    status = 0
    for name in chosen:
        start = time.perf_counter()
        code = main(commands[name])
        print(f"bench {name}: exit {code} after {time.perf_counter() - start:.0f} s", flush=True)
        status = status or code
    markdown = Path(args.markdown)
    command = "volren bench all --out " + str(out) + (f" --run-args {shlex.quote(args.run_args)}" if args.run_args else "")
    try:
        markdown.write_text(report.compose(out, markdown.resolve().parent, command=command))
    except OSError as exc:
        raise VolrenError(f"{markdown}: cannot write: {exc.strerror or exc}") from None
    print(f"wrote {markdown}")
    return status
