"""`volren bench run|skip|stress|app`: benchmarks that print numbers (medians of several runs).

`run` sweeps every renderer's quality settings (time against error), `skip` switches each skipping
technique on and off, `stress` feeds extreme input, `app` times the desktop app. The shared
datasets are found with --shared or $VOLREN_SHARED. The experiments behind the docs (pre-integration
tables, slicer settings, GPU runs, BENCHMARKS.md) are scripts in the repository's benchmarks/.
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
    add_fuzz_parser(kinds)
    add_scale_parser(kinds)


def add_scale_parser(kinds) -> None:
    s = kinds.add_parser("scale", help="time and peak memory against volume size, out of core and on a LocalCluster")
    s.add_argument("--sizes", default="256,512,1024,2048", help="volume sides n (n^3 uint16; default 256,512,1024,2048)")
    s.add_argument("--image", type=int, default=1024, help="image side in pixels (default 1024)")
    s.add_argument("--memory", default="2GB", help="chunk cache budget of each process (default 2GB)")
    s.add_argument("--frames", type=int, default=3, help="frames per measurement; the first is not counted (default 3)")
    s.add_argument("--cluster-size", type=int, default=512, help="volume side for the 1- and 2-worker runs (default 512)")
    s.add_argument("--renderer", default="slicer", help="a renderer that draws bricks (default slicer)")
    s.add_argument("--data", default="bench-data", help="folder for the generated OME-Zarr volumes (kept; default bench-data)")
    s.add_argument("--out", default="docs/bench", help="folder for scale.md and scale.json (default docs/bench)")
    s.set_defaults(run=run_scale_cmd)


def run_scale_cmd(args: argparse.Namespace) -> int:
    from volren.bench.scale import run_scale
    from volren.io.ome_zarr_io import parse_memory

    try:
        sizes = [int(v) for v in args.sizes.split(",") if v]
    except ValueError:
        raise VolrenError(f"--sizes takes numbers like 256,512, got {args.sizes!r}") from None
    for n in [*sizes, args.cluster_size]:
        if not 16 <= n <= 4096:
            raise VolrenError(f"--sizes and --cluster-size take sides from 16 to 4096, got {n}")
    if not 16 <= args.image <= 8192 or args.frames < 1:
        raise VolrenError("--image takes 16..8192 pixels and --frames at least 1")
    return run_scale(sizes, args.image, parse_memory(args.memory), args.frames, args.cluster_size, args.renderer,
                     Path(args.data), Path(args.out))  # fmt: skip


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
    k.add_argument("--samples", action="store_true", help="the bundled samples instead of the shared datasets")
    k.add_argument("--datasets", help="comma-separated (default: every shared dataset, or every sample)")
    k.add_argument("--styles", help="TF styles (default smooth,spiky,opaque)")
    k.add_argument("--renderers", help="comma-separated of slicer, tetra, vtk, shearwarp, objectorder, raycast (default: those installed)")
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
    with tqdm(total=skipping.row_count(kinds, renderers, base), desc="configurations", leave=False, disable=None) as bar:

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
    r.add_argument("--quick", action="store_true",
                   help="128x128, two bundled samples, 3 frames, a few settings per renderer (for CI)")
    r.add_argument("--out", default="bench-run", help="folder for runs.csv, <dataset>.png, summary.md")
    r.add_argument("--shared", help="the folder with data/ and scenes/ (default: $VOLREN_SHARED)")
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
    """`bench app`: the desktop app's latency and frame rate."""
    a = kinds.add_parser("app", help="desktop app: TF edit -> new frame latency, frames per second rotating")
    a.add_argument("--shared", help="the folder with data/ and scenes/ (default: $VOLREN_SHARED)")
    a.add_argument("--datasets", default="ironProt,bonsai", help="comma-separated (default ironProt,bonsai)")
    a.add_argument("--renderers", default="slicer,vtk", help="comma-separated (default slicer,vtk)")
    a.add_argument("--style", default="smooth", help="TF style of the scenes (default smooth)")
    a.add_argument("--edits", type=int, default=7, help="timed TF edits, median reported (default 7)")
    a.add_argument("--seconds", type=float, default=3.0, help="length of each drag gesture (default 3 s)")
    a.add_argument("--histogram-size", type=int, default=256,
                   help="time the 2D TF editor's joint histogram of an N^3 volume (default 256; 0: not)")
    a.add_argument("--gesture-scenes", default="bonsai/smooth,bonsai/spiky,oxygen/smooth",
                   help="dataset/style scenes whose gestures are timed with the renderer auto picks, at "
                        "947x896 (default bonsai/smooth,bonsai/spiky,oxygen/smooth; empty: none)")
    a.add_argument("--out", help="folder to write app.md into")
    a.set_defaults(run=run_app)


def run_app(args: argparse.Namespace) -> int:
    from volren.extras import require

    require("app", "volren bench app")  # before anything is loaded
    from volren.bench import app_gestures, app_latency
    from volren.bench.datasets import SCENES

    shared = shared_folder(args.shared)
    datasets = [d for d in args.datasets.split(",") if d]
    scenes = [tuple(s.split("/", 1)) if "/" in s else (s, args.style) for s in args.gesture_scenes.split(",") if s]
    unknown = [d for d in datasets + [d for d, _ in scenes] if d not in SCENES]
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
    if scenes:
        lines += ["", app_gestures.note(app.platformName(), args.seconds), "", app_gestures.HEADER]
        print("\n" + "\n".join(lines[-3:]), flush=True)
        for dataset, style in scenes:
            volume, tf = app_latency.scene_inputs(shared, dataset, style)
            for row in app_gestures.markdown_rows(app_gestures.measure_scene(app, volume, tf, f"{dataset}/{style}",
                                                                              args.seconds)):  # fmt: skip
                lines.append(row)
                print(row, flush=True)
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




def add_fuzz_parser(kinds) -> None:
    """`bench fuzz`: the malformed-input corpus through `volren render` (volren.bench.fuzz)."""
    f = kinds.add_parser("fuzz", help="malformed inputs through volren render: crashes, hangs, bad errors")
    f.add_argument("--quick", action="store_true", help="the subset CI runs (every 12th case and the seeds)")
    f.add_argument("--only", help="run the cases whose name contains this text")
    f.add_argument("--jobs", type=int, default=2, help="children at a time (default 2)")
    f.add_argument("--timeout", type=float, default=60.0, help="seconds before a case counts as a hang")
    f.add_argument("--exec", action="store_true", help="a fresh interpreter per case instead of a fork")
    f.add_argument("--seed", type=int, default=0, help="seed of the byte-level mutations (default 0)")
    f.add_argument("--report", metavar="OUT.md", help="write the summary and the failing cases there")
    f.add_argument("--work", help="folder for the cases' files (default: a temporary folder)")
    f.set_defaults(run=run_fuzz)


def run_fuzz(args: argparse.Namespace) -> int:
    import tempfile
    import time

    from tqdm import tqdm

    from volren.bench import fuzz
    from volren.bench.fuzz import report
    from volren.bench.fuzz.runner import run_cases
    from volren.io.safe_write import write_atomically

    if args.jobs < 1 or not args.timeout > 0:
        raise VolrenError("--jobs must be at least 1 and --timeout positive")
    cases = fuzz.quick_corpus(args.seed) if args.quick else fuzz.corpus(args.seed)
    if args.only:
        cases = [c for c in cases if args.only in c.name]
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="volren-fuzz-", dir=args.work) as work:
        with tqdm(total=len(cases), desc="fuzz", unit="case", disable=None) as bar:
            results = run_cases(cases, Path(work), args.jobs, args.timeout, "exec" if args.exec else "fork",
                                on_result=lambda r: bar.update(1))  # fmt: skip
    seconds = time.perf_counter() - start
    print(report.table(results))
    for r in report.failures(results):
        print(f"{r.outcome}: {r.case.name}: {r.detail} | {r.first_line}")
    if args.report:
        command = "volren bench fuzz" + (" --quick" if args.quick else "")
        text = report.markdown(results, command, seconds)
        write_atomically(Path(args.report), lambda tmp: tmp.write_text(text))
    print(f"{len(results)} cases in {seconds:.0f} s: {len(report.failures(results))} failures")
    return 1 if report.failures(results) else 0
