"""`python -m benchmarks.oneshot`: a one-shot `volren render`, stage by stage, first run against the next.

Why: the target is that a fresh install's first render of a bundled sample be at most 3 s slower
than the second, and a one-shot render's wall time cut stage by stage. Each case runs
`volren render --timings` in a new process (what a user's shell does), `runs` times in a row:
the first with an empty mesh cache (`VOLREN_MESH_CACHE` in a new folder: a mesh never seen
before), the others with what the first stored. The numba kernels' cache is what `volren
prepare` (run by scripts/setup.sh) left; delete it to measure compilation too.
"""

from __future__ import annotations

import argparse
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

#: (label, bundled sample, renderer); the shared cases are (dataset in SCENES, renderer)
SAMPLE_CASES = (("hollow_cylinder (sample)", "hollow_cylinder", "tetra"), ("hollow_cylinder (sample)", "hollow_cylinder", "reference"),
                ("phantom_ct (sample)", "phantom_ct", "auto"))  # fmt: skip
SHARED_CASES = (("oxygen", "tetra"), ("bonsai", "auto"))

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
    command = [sys.executable, "-m", "volren.cli.main", "render", *args, "-o", str(out), "--timings", "--force"]
    start = time.perf_counter()
    done = subprocess.run(command, env=env, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(command)}: {done.stderr.strip()[-300:]}")
    return wall, _stages(done.stderr)


def measure(args: argparse.Namespace) -> int:
    if args.runs < 1:
        raise VolrenError(f"--runs must be at least 1, got {args.runs}")
    cases = []
    for label, sample, renderer in SAMPLE_CASES:
        volume, tf = sample_paths(sample)
        cases.append((label, renderer, [str(volume), "--tf", str(tf), "--renderer", renderer]))
    shared = shared_folder(args.shared, required=False) if not args.samples_only else None
    if shared is not None:
        for name, renderer in SHARED_CASES:
            rel, scalars = SCENES[name][0], SCENES[name][1]
            flags = ["--scalars", scalars] if scalars else []
            tf = shared / "scenes" / f"{name}-smooth.json"
            cases.append((name, renderer, [str(shared / "data" / rel), *flags, "--tf", str(tf), "--renderer", renderer]))
    lines: list[str] = []

    def say(text: str = "") -> None:
        print(text, flush=True)
        lines.append(text)

    command = "python -m benchmarks.oneshot" + (f" --shared {args.shared}" if args.shared else "")
    say(f"Measured {datetime.date.today().isoformat()} by `{command}`: each case is `volren render ... --timings` "
        f"in a new process, {args.runs} times in a row, the first with an empty mesh cache (numba's cache as "
        "`volren prepare` left it). Seconds; *wall*: the process from start to exit; *frame: prepare* and *frame: "
        "tables*: what tetra's first frame paid for its mesh and pre-integration tables.")  # fmt: skip
    say()
    say(f"load average at the start: {' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    say()
    say("| case | renderer | run | wall | " + " | ".join(STAGES) + " |")
    say("|---|---|---|---:|" + "---:|" * len(STAGES))
    summary = []
    with tempfile.TemporaryDirectory(prefix="volren-oneshot-") as tmp:
        for i, (label, renderer, flags) in enumerate(cases):
            env = {**os.environ, "VOLREN_MESH_CACHE": str(Path(tmp) / f"meshes-{i}")}
            walls = []
            for k in range(args.runs):
                wall, stages = _render(flags, env, Path(tmp) / "out.png")
                walls.append(wall)
                cells = " | ".join(f"{stages[s]:.2f}" if s in stages else "" for s in STAGES)
                say(f"| {label} | {renderer} | {'first (no mesh cache)' if k == 0 else k + 1} | {wall:.2f} | {cells} |")
            summary.append((label, renderer, walls[0], statistics.median(walls[1:]) if len(walls) > 1 else walls[0]))
    say()
    say(f"load average at the end: {' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    say()
    say("| case | renderer | first run s | later runs s (median) | first - later s |")
    say("|---|---|---:|---:|---:|")
    for label, renderer, first, later in summary:
        say(f"| {label} | {renderer} | {first:.2f} | {later:.2f} | {first - later:+.2f} |")
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "oneshot.md").write_text("\n".join(lines) + "\n", encoding="utf-8")
    return 0


#: The columns: `volren render --timings`' stages and the parts of the frame renderers time themselves.
STAGES = ("start-up", "load", "set-up", "frame", "frame: prepare", "frame: tables", "write", "total")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.oneshot", description=__doc__.split("\n")[0])
    parser.add_argument("--shared", help="the folder with data/ and scenes/ (default: $VOLREN_SHARED; without it, "
                        "the bundled samples only)")  # fmt: skip
    parser.add_argument("--samples-only", action="store_true", help="only the bundled samples")
    parser.add_argument("--out", help="folder to write oneshot.md into (BENCHMARKS.md's section)")
    parser.add_argument("--runs", type=int, default=3, help="processes per case, the first with an empty mesh cache (default 3)")
    return run(measure, parser, argv)


if __name__ == "__main__":
    sys.exit(main())
