"""The plugin renderers' section of BENCHMARKS.md (`plugins.md`): shearwarp, objectorder (and the built-in
CPU ray caster raycast) against
VTK's mappers and the slicer at equal or lower error, Schulze et al.'s Table 1 for shearwarp and
Mora, Jessel and Caubet's Table 1 counters for objectorder, each with the command that made it.

    python -m benchmarks.plugins_report [--out docs/bench] [--shared DIR] [--datasets ...]

Runs, in this order (about 30 minutes on the project's 2-core machine):
1. `volren bench run` on the shared uniform datasets with both plugins and their peers (OUT/plugins/runs.csv);
2. `benchmarks.ratios` on that file for each plugin: per dataset and TF, the ratio (peer ms / ours)
   at each peer's fastest setting that the plugin reaches at equal or lower RMSE;
3. `benchmarks.shearwarp_table1` and `benchmarks.objectorder_table`, their output kept as printed.
The machine's load average is printed with each part (every time shares the cores with whatever
else runs; the ratios compare renderers timed in the same run).
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import datetime
import io
import os
import subprocess
import sys
from pathlib import Path

from benchmarks.machine_speed import machine_line
from benchmarks.ratios import ratios
from volren.cli.main import main as volren_main

PLUGINS = ("shearwarp", "objectorder")
#: Our CPU renderers compared the same way: the two plugins and the built-in image-order ray caster.
OURS = (*PLUGINS, "raycast")
PEERS = ("vtk-fixed_point", "vtk-gpu", "vtk-smart", "slicer")
DATASETS = "bonsai,engine,aneurism,ironProt"


def load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def ratio_table(rows: list[dict], ours: str) -> list[str]:
    """Per dataset and TF, ours against each peer at the peer's fastest setting that ours reaches."""
    found = ratios(rows, ours)
    present = {r["renderer"] for r in rows}
    peers = [p for p in (*PEERS, *(x for x in OURS if x != ours)) if p in present]
    lines = [f"| dataset | TF | {' | '.join(peers)} |", "|---|---|" + "---:|" * len(peers)]
    keys = sorted({(r["dataset"], r["tf"]) for r in rows if r["renderer"] == ours})
    for dataset, tf in keys:
        cells = []
        for peer in peers:
            items = found.get((dataset, tf, peer))
            if not items:
                cells.append("not reached")
                continue
            fastest = min(items, key=lambda i: i[1])
            cells.append(f"{fastest[0]:.2f} ({fastest[2]}, {fastest[1]:.0f} ms)")
        lines.append(f"| {dataset} | {tf} | {' | '.join(cells)} |")
    return lines


def module_output(args: list[str], shared: str) -> str:
    """A benchmark module's printed output (run as its own process, as its docstring says to run it)."""
    env = dict(os.environ, VOLREN_SHARED=shared)
    done = subprocess.run([sys.executable, "-m", *args], capture_output=True, text=True, check=False, env=env)
    text = "\n".join(line for line in done.stdout.splitlines() if line.strip())
    if done.returncode:
        text += f"\n(exit {done.returncode}: {done.stderr.strip().splitlines()[-1] if done.stderr.strip() else ''})"
    return text


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.plugins_report", description=__doc__.splitlines()[0]
    )
    parser.add_argument("--out", type=Path, default=Path("docs/bench"))
    parser.add_argument("--shared", default=os.environ.get("VOLREN_SHARED", "../shared"))
    parser.add_argument("--datasets", default=DATASETS)
    args = parser.parse_args(argv)
    folder = args.out / "plugins"
    lines = [
        f"Measured {datetime.date.today().isoformat()} by `python -m benchmarks.plugins_report --out {args.out}`.",
        "",
    ]

    start, speed = load(), machine_line()
    run_args = ["bench", "run", "--shared", args.shared, "--datasets", args.datasets,
                "--renderers", ",".join((*OURS, *PEERS)), "--out", str(folder)]  # fmt: skip
    with contextlib.redirect_stdout(io.StringIO()):
        code = volren_main(run_args)
    if code:
        print(f"volren {' '.join(run_args)} failed (exit {code})", file=sys.stderr)
        return code
    with (folder / "runs.csv").open() as f:
        rows = list(csv.DictReader(f))
    lines += [
        "### Speed at equal or lower error",
        "",
        f"`volren {' '.join(run_args)}` (512x512, median of warm frames with the camera turning; load average "
        f"{start} at the start, {load()} at the end; {speed} at the start, {machine_line()} at the end), then "
        f"`python -m benchmarks.ratios {folder}/runs.csv RENDERER`. "
        "Each cell: peer ms / ours at the peer's fastest setting that ours reaches at equal or lower RMSE "
        "(above 1: ours is faster), with that setting and its time.",
    ]
    for ours in OURS:
        lines += ["", f"**{ours}**", "", *ratio_table(rows, ours)]

    table1 = ["benchmarks.shearwarp_table1", "--shared", args.shared]
    text = module_output(table1, args.shared)
    lines += [
        "",
        "### Schulze et al.'s Table 1 (shearwarp, seconds per frame)",
        "",
        f"`python -m {' '.join(table1)}`",
        "",
    ]
    for line in text.splitlines():  # the table as Markdown, the load lines as paragraphs around it
        lines += [line] if line.startswith("|") else ["", line, ""]
    counters = ["benchmarks.objectorder_table", args.datasets, "smooth,spiky,opaque", "256", "5"]
    lines += ["", "### Mora et al.'s Table 1 (objectorder: counters, hidden volume removal on and off)", "",
              f"`VOLREN_SHARED={args.shared} python -m {' '.join(counters)}`", "",
              "```", module_output(counters, args.shared), "```"]  # fmt: skip
    (args.out / "plugins.md").write_text("\n".join(lines) + "\n", encoding="utf-8")
    print(f"wrote {args.out / 'plugins.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
