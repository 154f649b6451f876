"""`volren bench run|skip|stress|app`: benchmarks that print numbers (medians of several runs).

`run` sweeps every renderer's quality settings (time against error), `skip` switches each skipping
technique on and off, `stress` feeds extreme input, `app` times the desktop app's gestures (the app
measures itself: `volren.app.timing`, imported only when run). The shared datasets are found with
--shared or $VOLREN_SHARED. The experiments behind the docs (the fuzz corpus, scaling, the app's TF
edit latency, the quality levels' derivation, pre-integration tables, GPU runs, BENCHMARKS.md) are scripts in the repository's
benchmarks/, run as `python -m benchmarks.NAME`.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from volren.bench.datasets import shared_folder
from volren.errors import VolrenError


def add_parser(sub) -> None:
    bench = sub.add_parser("bench", help="benchmarks (print tables of times and errors)")
    kinds = bench.add_subparsers(dest="bench", metavar="BENCHMARK", required=True)
    add_skip_parser(kinds)
    add_run_parser(kinds)
    add_stress_parser(kinds)
    add_app_parsers(kinds)


def float_list(text: str, what: str) -> list[float]:
    """Comma-separated positive finite numbers, or a one-line error naming `what`."""
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise VolrenError(f"{what} must be comma-separated numbers, got {text!r}") from None
    if not values or not all(v > 0 and math.isfinite(v) for v in values):
        raise VolrenError(f"{what} must be positive finite numbers, got {text!r}")
    return values


def add_skip_parser(kinds) -> None:
    """`bench skip`: each skipping technique on and off per renderer (volren.bench.skipping)."""
    k = kinds.add_parser("skip", help="skipping techniques on and off: ms, work counters, image change")
    k.add_argument("--shared", help="the folder with data/ and scenes/ (default: $VOLREN_SHARED)")
    k.add_argument(
        "--samples", action="store_true", help="the bundled samples instead of the shared datasets"
    )
    k.add_argument("--datasets", help="comma-separated (default: every shared dataset, or every sample)")
    k.add_argument("--styles", help="TF styles (default smooth,spiky,opaque)")
    k.add_argument(
        "--renderers",
        help="comma-separated of slicer, tetra, vtk, shearwarp, objectorder, raycast (default: those installed)",
    )
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
    if args.renderers is None:
        from volren.renderers.registry import registry

        renderers = [r for r in skipping.RENDERERS if r in registry.names()]
    else:
        renderers = [r for r in args.renderers.split(",") if r]
    if not renderers or set(renderers) - set(skipping.RENDERERS):
        names = ", ".join(skipping.RENDERERS)
        raise VolrenError(f"--renderers must name some of {names}, got {args.renderers!r}")
    shared = None if args.samples else shared_folder(args.shared)
    kinds, scenes = skipping.plan(shared, args.samples, args.datasets, args.styles, args.quick)
    base = RenderSettings(step=args.step, preintegration=args.preintegration)
    print(skipping.HEADER)
    with tqdm(
        total=skipping.row_count(kinds, renderers, base), desc="configurations", leave=False, disable=None
    ) as bar:

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


# --------------------------------------------------------------------------------------- bench run
def add_run_parser(kinds) -> None:
    r = kinds.add_parser("run", help="every renderer and quality setting: ms against error, CSV, plots")
    r.add_argument(
        "--quick",
        action="store_true",
        help="128x128, two bundled samples, 3 frames, a few settings per renderer (for CI)",
    )
    r.add_argument("--out", default="bench-run", help="folder for runs.csv, <dataset>.png, summary.md")
    r.add_argument("--shared", help="the folder with data/ and scenes/ (default: $VOLREN_SHARED)")
    r.add_argument("--datasets", help="comma-separated (default: every shared dataset and bundled sample)")
    r.add_argument("--tfs", help="TF styles to keep, e.g. smooth,spiky (default: all)")
    r.add_argument(
        "--renderers",
        help="curves to run, e.g. slicer,vtk-gpu,tetra,vtk-raycast, or any registered "
        "renderer (a plugin: swept along its declared quality axis) (default: the built-in curves)",
    )
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
    steps = float_list(args.steps, "--steps") if args.steps else None
    curves = sweep.check_curves(_names(args.renderers)) if args.renderers else None
    shared = shared_folder(args.shared, required=False)  # none: the bundled samples only
    chosen = datasets.select(_names(args.datasets), shared, args.quick)
    styles = _names(args.tfs)

    def configs(kind: str) -> list:
        return sweep.configs(kind, args.quick, steps, curves)

    total = sum(len(configs(d.kind)) for d in chosen for s in d.styles if styles is None or s in styles)
    out = Path(args.out)
    try:
        out.mkdir(parents=True, exist_ok=True)
        stream = (out / "runs.csv").open("w", newline="")
    except OSError as exc:
        raise VolrenError(f"{out}: cannot write: {exc.strerror or exc}") from None
    start, rows, skipped = time.perf_counter(), [], []
    with stream, tqdm(total=total, desc="bench run", unit="run", leave=False, disable=None) as bar:

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


# ------------------------------------------------------------------------------------ bench stress
def add_stress_parser(kinds) -> None:
    """`bench stress`: NaN/Inf/out-of-range pixels and error against reference on extreme input."""
    t = kinds.add_parser("stress", help="numerical stability: NaN/Inf/out-of-range counts on extreme input")
    t.add_argument(
        "--quick", action="store_true", help="a subset of the scenes and tables (well under a minute)"
    )
    t.add_argument("--out", help="folder to write stress.csv and stress.md into (default: write nothing)")
    t.add_argument("--size", type=int, default=64, help="image side in pixels (default 64)")
    t.add_argument(
        "--renderers", help="comma-separated renderers besides reference (default: all registered)"
    )
    t.add_argument(
        "--cases", help="comma-separated globs of scene names, e.g. 'tet-*,*/spike' (default: all)"
    )
    t.add_argument("--suites", default="images,tables", help="images, tables or both (default: both)")
    t.add_argument(
        "--eps",
        type=float,
        default=None,
        help="how far a premultiplied colour may exceed its alpha "
        "(default 1e-4; 8-bit output rounds by up to 1/255)",
    )
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
    with tqdm(total=len(work), desc="stress", unit="run", leave=False, disable=None) as bar:

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
            (out / "stress.md").write_text(
                stress.markdown(rows, seconds, args.size, args.quick, work.notes, eps)
            )
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
    """`bench app`: the desktop app's gestures with the renderer `auto` picks."""
    a = kinds.add_parser("app", help="desktop app: previews per second, release to full frame and GUI stalls "
                         "of each gesture")  # fmt: skip
    a.add_argument("--shared", help="the folder with data/ and scenes/ (default: $VOLREN_SHARED)")
    a.add_argument("--scenes", default="bonsai/smooth,bonsai/spiky,oxygen/smooth",
                   help="dataset/style scenes whose gestures are timed with the renderer auto picks, at 947x896 "
                        "(default bonsai/smooth,bonsai/spiky,oxygen/smooth)")  # fmt: skip
    a.add_argument("--seconds", type=float, default=3.0, help="length of each gesture (default 3 s)")
    a.add_argument("--out", help="folder to write app.md into")
    a.set_defaults(run=run_app)


def run_app(args: argparse.Namespace) -> int:
    from volren.extras import require

    require("app", "volren bench app")  # before anything is loaded
    from volren.app.timing import gestures
    from volren.bench.datasets import SCENES, scene_inputs

    shared = shared_folder(args.shared)
    scenes = [tuple(s.split("/", 1)) if "/" in s else (s, "smooth") for s in args.scenes.split(",") if s]
    unknown = [d for d, _ in scenes if d not in SCENES]
    if not scenes or unknown:
        raise VolrenError(f"--scenes must name datasets of {', '.join(SCENES)}, got {args.scenes!r}")
    if not (math.isfinite(args.seconds) and args.seconds > 0):
        raise VolrenError("--seconds must be positive")
    app = gestures.application()
    lines = [gestures.HEADER]
    print(gestures.HEADER, flush=True)
    for dataset, style in scenes:
        volume, tf = scene_inputs(shared, dataset, style)
        for row in gestures.markdown_rows(
            gestures.measure_scene(app, volume, tf, f"{dataset}/{style}", args.seconds)
        ):
            lines.append(row)
            print(row, flush=True)
    if args.out:
        out = Path(args.out)
        try:
            out.mkdir(parents=True, exist_ok=True)
            (out / "app.md").write_text(
                gestures.note(app.platformName(), args.seconds) + "\n\n" + "\n".join(lines) + "\n"
            )
        except OSError as exc:
            raise VolrenError(f"{args.out}: cannot write: {exc.strerror or exc}") from None
    return 0
