"""`python -m benchmarks.fuzz [--quick]`: the malformed-input corpus through `volren render` and the
other commands; exit status 1 when any case crashed, hung or failed otherwise (docs/fuzz.md)."""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

from benchmarks._cli import run
from benchmarks.fuzz import corpus, quick_corpus, report
from benchmarks.fuzz.runner import run_cases
from volren.errors import VolrenError

COMMAND = "python -m benchmarks.fuzz"


def fuzz(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from volren.io.safe_write import write_atomically

    if args.jobs < 1 or not args.timeout > 0:
        raise VolrenError("--jobs must be at least 1 and --timeout positive")
    cases = quick_corpus(args.seed) if args.quick else corpus(args.seed)
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
        command = COMMAND + (" --quick" if args.quick else "")
        text = report.markdown(results, command, seconds)
        write_atomically(Path(args.report), lambda tmp: tmp.write_text(text))
    print(f"{len(results)} cases in {seconds:.0f} s: {len(report.failures(results))} failures")
    return 1 if report.failures(results) else 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog=COMMAND, description="malformed inputs through volren: crashes, hangs, "
                                     "bad errors")  # fmt: skip
    parser.add_argument(
        "--quick", action="store_true", help="the subset CI runs (every 12th case and the seeds)"
    )
    parser.add_argument("--only", help="run the cases whose name contains this text")
    parser.add_argument("--jobs", type=int, default=2, help="children at a time (default 2)")
    parser.add_argument("--timeout", type=float, default=60.0, help="seconds before a case counts as a hang")
    parser.add_argument("--exec", action="store_true", help="a fresh interpreter per case instead of a fork")
    parser.add_argument("--seed", type=int, default=0, help="seed of the byte-level mutations (default 0)")
    parser.add_argument("--report", metavar="OUT.md", help="write the summary and the failing cases there")
    parser.add_argument("--work", help="folder for the cases' files (default: a temporary folder)")
    return run(fuzz, parser, argv)


if __name__ == "__main__":
    sys.exit(main())
