"""`python -m benchmarks.oneshot`: a one-shot `volren render`, stage by stage, first run against the next,
and against the same render with `--renderer vtk`.

Why: the targets are that a fresh install's first render of a bundled sample be at most 3 s slower
than the second, and that a one-shot `volren render IN -o OUT.png` with no options take at most
0.6x the wall time of `volren render IN -o OUT.png --renderer vtk`; a one-shot render's wall time
is cut stage by stage. Each case runs `volren render --timings` in a new process (what a user's
shell does), `runs` times in a row: the first with empty mesh and step caches
(`VOLREN_MESH_CACHE`, `VOLREN_STEP_CACHE` in new folders: a mesh and a scene never seen before),
the others with what the first stored. The numba kernels' cache is what `volren prepare` (run by
scripts/setup.sh) left; delete it to measure compilation too. The start-up's imports are
measured apart with ``python -X importtime`` (the sum of the top-level imports' cumulative
times, less sensitive to a loaded machine than wall times).
"""

from __future__ import annotations

import argparse
import compileall
import datetime
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from benchmarks._cli import run
from volren.bench.datasets import SCENES, shared_folder
from volren.errors import VolrenError
from volren.samples import sample_paths

#: The renderer of a render with no --renderer (what `volren render IN -o OUT.png` draws with).
DEFAULT = "default"
#: (label, bundled sample, renderer); the shared cases are (dataset in SCENES, renderer). Every
#: DEFAULT case is measured with `--renderer vtk` too (the ratio's denominator).
SAMPLE_CASES = (("hollow_cylinder (sample)", "hollow_cylinder", "tetra"), ("hollow_cylinder (sample)", "hollow_cylinder", "reference"),
                ("phantom_ct (sample)", "phantom_ct", DEFAULT), ("marschner_lobb (sample)", "marschner_lobb", DEFAULT),
                ("hollow_cylinder (sample)", "hollow_cylinder", DEFAULT))  # fmt: skip
SHARED_CASES = (("oxygen", "tetra"), *((name, DEFAULT) for name in ("bonsai", "engine", "aneurism", "ironProt", "oxygen",
                                                                    "bluntfin", "spx")))  # fmt: skip

_STAGE = re.compile(r"([\w-]+) ([\d.]+) s")


def _stages(stderr: str) -> dict[str, float]:
    """{stage: seconds} from `--timings`' line, with the frame's parts as "frame: part" and the total."""
    line = next((ln for ln in stderr.splitlines() if "timings:" in ln), None)
    if line is None:
        raise RuntimeError(f"no timings in the output: {stderr.strip()[-300:]}")
    body, total = line.split("timings:", 1)[1].rsplit("; total", 1)
    out: dict[str, float] = {}
    for part in re.split(r",\s*(?![^()]*\))", body.strip()):
        name, seconds = _STAGE.match(part.strip()).groups()  # type: ignore[union-attr]
        out[name] = float(seconds)
        inner = re.search(r"\((.*)\)", part)
        if inner:
            for sub in inner.group(1).split(","):
                sub_name, sub_s = _STAGE.match(sub.strip()).groups()  # type: ignore[union-attr]
                out[f"{name}: {sub_name}"] = float(sub_s)
    out["total"] = float(total.strip().split()[0])
    return out


def _render(args: list[str], env: dict[str, str], out: Path) -> tuple[float, dict[str, float]]:
    """(wall seconds of the process, its stages)."""
    command = [
        sys.executable,
        "-m",
        "volren.cli.main",
        "render",
        *args,
        "-o",
        str(out),
        "--timings",
        "--force",
    ]
    start = time.perf_counter()
    done = subprocess.run(command, env=env, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(command)}: {done.stderr.strip()[-300:]}")
    return wall, _stages(done.stderr)


def import_seconds(args: list[str], env: dict[str, str], out: Path) -> tuple[float, list[tuple[str, float]]]:
    """(seconds of all top-level imports, the slowest five as (module, seconds)) of a render, from
    ``-X importtime`` (microseconds per module; a top-level import's line names it unindented)."""
    command = [
        sys.executable,
        "-X",
        "importtime",
        "-m",
        "volren.cli.main",
        "render",
        *args,
        "-o",
        str(out),
        "--force",
    ]
    done = subprocess.run(command, env=env, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(command)}: {done.stderr.strip()[-300:]}")
    top = []
    for line in done.stderr.splitlines():
        if line.startswith("import time:") and "|" in line:
            _, cumulative, name = line.split("|")
            if cumulative.strip().isdigit() and not name.startswith("  "):
                top.append((name.strip(), int(cumulative) / 1e6))
    return sum(s for _, s in top), sorted(top, key=lambda item: -item[1])[:5]


#: A new interpreter's numba: its import, raycast's kernel module, and the first call of its march on a
#: 2x2x2 grid (numba loads the cached machine code and its own typing registries then); seconds of each.
_NUMBA_PROBE = """
import time
start = time.perf_counter()
import numpy as np
import numba
numba_s = time.perf_counter() - start
start = time.perf_counter()
from volren.renderers.raycast import march
from volren.renderers.raycast.march_inputs import Classification, EmptyBricks, PixelView
module_s = time.perf_counter() - start
view = PixelView(np.eye(4), 2, 2, np.zeros(3), np.ones(3), np.array([0.0, 0.0, 1.0]), 10.0, np.zeros(4),
                 np.zeros((0, 4)))
table = np.zeros((2, 2, 4), np.float32)
table.flags.writeable = False  # read-only, as the renderer hands it: the specialization set-up compiled
classes = Classification(False, np.zeros((16, 4)), table, 1.0, 0.0, 1.0, False)
start = time.perf_counter()
march.march(np.zeros((2, 2, 2), np.uint8), EmptyBricks(np.zeros((1, 1, 1), np.int8), 4), view, classes, 0.99,
            np.zeros(1, np.int64), np.zeros((4, 4), np.float32), np.zeros((1, 4), np.int64))
print(numba_s, module_s, time.perf_counter() - start)
"""


def numba_fixed_seconds(env: dict[str, str]) -> tuple[float, float, float]:
    """(import numba, import raycast's kernels, their first call) in a new interpreter: what a one-shot
    raycast render pays before its first sample, and `--renderer vtk` does not."""
    done = subprocess.run(
        [sys.executable, "-c", _NUMBA_PROBE], env=env, capture_output=True, text=True, check=False
    )
    if done.returncode != 0:
        raise RuntimeError(f"the numba probe failed: {done.stderr.strip()[-300:]}")
    numba_s, module_s, first_call_s = (float(x) for x in done.stdout.split())
    return numba_s, module_s, first_call_s


def user_environment() -> dict[str, str]:
    """This environment less PYTHONDONTWRITEBYTECODE: a user's Python reads the bytecode that
    installing volren compiled (a sandbox that sets the variable would compile every module of
    volren at every start, about 0.13 s here)."""
    return {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}


def compile_volren() -> None:
    """volren's modules compiled to bytecode, as `pip install` leaves a wheel's."""
    import volren

    compileall.compile_dir(Path(volren.__file__).parent, quiet=1)


def _with_renderer(flags: list[str], renderer: str) -> list[str]:
    return flags if renderer == DEFAULT else [*flags, "--renderer", renderer]


def measure(args: argparse.Namespace) -> int:
    if args.runs < 1:
        raise VolrenError(f"--runs must be at least 1, got {args.runs}")
    cases = []
    for label, sample, renderer in SAMPLE_CASES:
        volume, tf = sample_paths(sample)
        cases.append((label, renderer, _with_renderer([str(volume), "--tf", str(tf)], renderer)))
    shared = shared_folder(args.shared, required=False) if not args.samples_only else None
    if shared is not None:
        for name, renderer in SHARED_CASES:
            rel, scalars = SCENES[name][0], SCENES[name][1]
            flags = ["--scalars", scalars] if scalars else []
            tf = shared / "scenes" / f"{name}-smooth.json"
            if (shared / "data" / rel).is_file() and tf.is_file():
                cases.append(
                    (
                        name,
                        renderer,
                        _with_renderer([str(shared / "data" / rel), *flags, "--tf", str(tf)], renderer),
                    )
                )
    groups = [[(label, renderer, flags), *([(label, "vtk", [*flags, "--renderer", "vtk"])] if renderer == DEFAULT else [])]
              for label, renderer, flags in cases]  # fmt: skip
    cases = [case for group in groups for case in group]
    lines: list[str] = []

    def say(text: str = "") -> None:
        print(text, flush=True)
        lines.append(text)

    command = "python -m benchmarks.oneshot" + (f" --shared {args.shared}" if args.shared else "")
    say(f"Measured {datetime.date.today().isoformat()} by `{command}`: each case is `volren render ... --timings` "
        f"in a new process, {args.runs} times, the first with empty mesh and step caches (numba's cache as "
        "`volren prepare` left it); a render with no --renderer and its `--renderer vtk` twin run in turns. "
        "volren's modules are compiled to bytecode first, as installing a wheel leaves them. Seconds; *wall*: the "
        "process from start to exit; *frame: prepare* and *frame: tables*: what tetra's first frame paid for its "
        "mesh and pre-integration tables; *frame: step_choice*: what raycast's error target paid for its step (a "
        f"search, or the cached step); *{DEFAULT}*: no --renderer.")  # fmt: skip
    say()
    say(f"load average at the start: {' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    say()
    say("| case | renderer | run | wall | " + " | ".join(STAGES) + " |")
    say("|---|---|---|---:|" + "---:|" * len(STAGES))
    summary = []
    compile_volren()
    with tempfile.TemporaryDirectory(prefix="volren-oneshot-") as tmp:
        for g, group in enumerate(groups):
            env = {case[1]: {**user_environment(), "VOLREN_MESH_CACHE": str(Path(tmp) / f"meshes-{g}-{case[1]}"),
                             "VOLREN_STEP_CACHE": str(Path(tmp) / f"steps-{g}-{case[1]}")} for case in group}  # fmt: skip
            walls: dict[str, list[float]] = {case[1]: [] for case in group}
            rows: dict[str, list[str]] = {case[1]: [] for case in group}
            for k in range(args.runs):
                for label, renderer, flags in group if k % 2 == 0 else group[::-1]:
                    wall, stages = _render(flags, env[renderer], Path(tmp) / "out.png")
                    walls[renderer].append(wall)
                    cells = " | ".join(f"{stages[s]:.2f}" if s in stages else "" for s in STAGES)
                    run_name = "first (no caches)" if k == 0 else k + 1
                    rows[renderer].append(f"| {label} | {renderer} | {run_name} | {wall:.2f} | {cells} |")
            for label, renderer, _ in group:
                for row in rows[renderer]:
                    say(row)
                w = walls[renderer]
                summary.append((label, renderer, w[0], statistics.median(w[1:]) if len(w) > 1 else w[0]))
    say()
    say(f"load average at the end: {' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    say()
    vtk = {label: (first, later) for label, renderer, first, later in summary if renderer == "vtk"}
    say(
        "| case | renderer | first run s | later runs s (median) | first - later s | first / vtk's | later / vtk's |"
    )
    say("|---|---|---:|---:|---:|---:|---:|")
    for label, renderer, first, later in summary:
        ratios = (f"{first / vtk[label][0]:.2f} | {later / vtk[label][1]:.2f}" if renderer == DEFAULT and label in vtk
                  else " | ")  # fmt: skip
        say(f"| {label} | {renderer} | {first:.2f} | {later:.2f} | {first - later:+.2f} | {ratios} |")
    label, renderer, flags = next(c for c in cases if (c[0].startswith(args.importtime_case) if args.importtime_case
                                                       else c[1] == DEFAULT))  # fmt: skip
    with tempfile.TemporaryDirectory(prefix="volren-oneshot-") as tmp:
        total, slowest = import_seconds(flags, user_environment(), Path(tmp) / "out.png")
    say()
    say(f"imports of `volren render` ({label}, {renderer}; `-X importtime`, top-level modules' cumulative): "
        f"{total:.2f} s; slowest: " + ", ".join(f"{name} {s:.2f} s" for name, s in slowest))  # fmt: skip
    numba_s, module_s, first_call_s = numba_fixed_seconds(user_environment())
    say()
    say(f"numba's fixed cost in a new interpreter (`benchmarks.oneshot.numba_fixed_seconds`): import numba "
        f"{numba_s:.2f} s, raycast's kernel module {module_s:.2f} s, the first call of its march on a 2x2x2 grid "
        f"(the cached machine code loaded) {first_call_s:.2f} s; {numba_s + module_s + first_call_s:.2f} s in all, "
        "paid by every one-shot render that draws with a numba kernel (not raycast's 1D frames where its C march builds) and by none with `--renderer vtk`.")  # fmt: skip
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "oneshot.md").write_text("\n".join(lines) + "\n", encoding="utf-8")
    return 0


#: The columns: `volren render --timings`' stages and the parts of the frame renderers time themselves.
STAGES = (
    "start-up",
    "load",
    "set-up",
    "frame",
    "frame: prepare",
    "frame: tables",
    "frame: step_choice",
    "write",
    "total",
)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.oneshot", description=__doc__.split("\n")[0])
    parser.add_argument("--shared", help="the folder with data/ and scenes/ (default: $VOLREN_SHARED; without it, "
                        "the bundled samples only)")  # fmt: skip
    parser.add_argument("--samples-only", action="store_true", help="only the bundled samples")
    parser.add_argument("--out", help="folder to write oneshot.md into (BENCHMARKS.md's section)")
    parser.add_argument(
        "--runs", type=int, default=3, help="processes per case, the first with empty caches (default 3)"
    )
    parser.add_argument(
        "--importtime-case",
        help="the case (label's start) whose imports are measured (default: the first drawn with no --renderer)",
    )
    return run(measure, parser, argv)


if __name__ == "__main__":
    sys.exit(main())
