"""`python -m benchmarks.ratios RUNS.csv RENDERER`: one renderer's speed against each other
renderer at equal or lower error, from one `volren bench run`'s runs.csv.

For every setting of every other renderer (a row of runs.csv), the fastest setting of RENDERER
whose RMSE is at most that row's, and the time ratio (other ms / ours ms: above 1, ours is faster).
Prints, per TF and peer renderer, the ratio at the peer's fastest setting that RENDERER reaches and
the range over all the peer's settings it reaches. `--fragment FILE` also writes that table with the
command that made it and a line per peer (BENCHMARKS.md's section on shear-warp's peers is
`--fragment docs/bench/shearwarp_peers.md`), so the report is regenerated, not edited by hand.
"""

from __future__ import annotations

import argparse
import csv
import statistics
import sys
from collections import defaultdict
from pathlib import Path


def ratios(rows: list[dict], ours: str) -> dict[tuple[str, str, str], list[tuple[float, float, str, str]]]:
    """(dataset, tf, peer) -> [(ratio, peer ms, peer settings, our settings)] over the peer's rows we reach."""
    mine = defaultdict(list)
    for r in rows:
        if r["renderer"] == ours:
            mine[r["dataset"], r["tf"]].append((float(r["rmse"]), float(r["ms"]), r["settings"]))
    out: dict[tuple[str, str, str], list[tuple[float, float, str, str]]] = defaultdict(list)
    for r in rows:
        if r["renderer"] == ours:
            continue
        reach = [m for m in mine[r["dataset"], r["tf"]] if m[0] <= float(r["rmse"])]
        if reach:
            best = min(reach, key=lambda m: m[1])
            out[r["dataset"], r["tf"], r["renderer"]].append(
                (float(r["ms"]) / best[1], float(r["ms"]), r["settings"], best[2])
            )
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.ratios", description=__doc__.split("\n")[0])
    parser.add_argument("runs", type=Path, help="runs.csv of `volren bench run`")
    parser.add_argument("renderer", help="the renderer measured against the others")
    parser.add_argument("--fragment", type=Path, help="also write the table as a BENCHMARKS.md fragment here")
    args = parser.parse_args(argv)
    with args.runs.open() as f:
        rows = list(csv.DictReader(f))
    found = ratios(rows, args.renderer)
    table = ["| dataset | TF | peer | ratio at the peer's fastest setting reached | range over the peer's settings reached |",
             "|---|---|---|---|---|"]  # fmt: skip
    at_fastest: dict[str, list[float]] = defaultdict(list)
    for (dataset, tf, peer), items in sorted(found.items()):
        fastest = min(items, key=lambda i: i[1])
        at_fastest[peer].append(fastest[0])
        lo, hi = min(i[0] for i in items), max(i[0] for i in items)
        table.append(f"| {dataset} | {tf} | {peer} | {fastest[0]:.2f} ({fastest[2]}: {fastest[1]:.0f} ms; ours: "
                     f"{fastest[3]}) | {lo:.2f}-{hi:.2f} ({len(items)} settings) |")  # fmt: skip
    print("\n".join(table))
    if args.fragment is not None:
        scenes = {(r["dataset"], r["tf"]) for r in rows if r["renderer"] == args.renderer}
        summary = [f"- against `{peer}`: {min(v):.2f}-{max(v):.2f}x at its fastest setting reached, on {len(v)} of "
                   f"{len(scenes)} scenes (median {statistics.median(v):.2f}x)" for peer, v in sorted(at_fastest.items())]  # fmt: skip
        command = f"python -m benchmarks.ratios {args.runs} {args.renderer} --fragment {args.fragment}"
        text = [f"From `{args.runs}` (the rows of one `volren bench run`), by `{command}`: `{args.renderer}` against "
                "each peer setting at equal or lower RMSE, the peer's time over ours (above 1: ours is faster), "
                "ratios within the one run.", "", *summary, "", *table]  # fmt: skip
        try:
            args.fragment.write_text("\n".join(text) + "\n", encoding="utf-8")
        except OSError as exc:
            print(f"error: {args.fragment}: cannot write: {exc.strerror or exc}", file=sys.stderr)
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
