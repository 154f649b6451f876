"""`volren check-renderer NAME [--quick]`: the conformance kit (`volren.testing`) on one renderer.

Prints one line per measurement (PASS or FAIL, the measured number and its bound) as each check
finishes, then a summary; exits 0 when every check passes and 1 otherwise.
"""

from __future__ import annotations

import argparse


def _positive(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not value > 0:
        raise argparse.ArgumentTypeError(f"expected a positive number of seconds, got {text!r}")
    return value


def add_parser(sub) -> None:
    p = sub.add_parser("check-renderer", help="run the conformance kit on a registered renderer")
    p.add_argument("name", help="registered renderer name (see `volren renderers`)")
    p.add_argument(
        "--quick", action="store_true", help="fewer cases (fewer steps and capability combinations)"
    )
    p.add_argument("--check", action="append", metavar="CHECK", help="run only this check (repeatable)")
    p.add_argument(
        "--time-limit", type=_positive, default=None, metavar="S", help="seconds per check (default 300)"
    )
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from volren.testing.runner import DEFAULT_TIME_LIMIT, run_checks, select_checks

    checks = select_checks(args.check)
    failed = 0
    for result in run_checks(args.name, args.quick, args.check, args.time_limit or DEFAULT_TIME_LIMIT):
        for line in result.lines():
            print(line, flush=True)
        failed += not result.passed
    verdict = "conformant" if not failed else f"{failed} of {len(checks)} checks failed"
    print(f"{args.name}: {len(checks) - failed} of {len(checks)} checks passed: {verdict}", flush=True)
    return 1 if failed else 0
