"""The fuzz suite's summary: outcomes per input group, and every failing case with its first line."""

from __future__ import annotations

from collections import Counter

from benchmarks.fuzz.runner import FAILURES, OUTCOMES, Result


def failures(results: list[Result]) -> list[Result]:
    return [r for r in results if r.outcome in FAILURES]


def table(results: list[Result]) -> str:
    """A Markdown table: one row per group, one column per outcome seen, and the totals."""
    seen = [o for o in OUTCOMES if any(r.outcome == o for r in results)]
    groups = sorted({r.case.group for r in results})
    counts = {g: Counter(r.outcome for r in results if r.case.group == g) for g in groups}
    lines = ["| input | cases | " + " | ".join(seen) + " |", "|---|---:|" + "---:|" * len(seen)]
    for g in groups:
        row = [str(counts[g][o]) if counts[g][o] else "" for o in seen]
        lines.append(f"| {g} | {sum(counts[g].values())} | " + " | ".join(row) + " |")
    total = Counter(r.outcome for r in results)
    lines.append(f"| **all** | **{len(results)}** | " + " | ".join(f"**{total[o]}**" for o in seen) + " |")
    return "\n".join(lines)


def markdown(results: list[Result], command: str, seconds: float) -> str:
    bad = failures(results)
    out = [
        "# Fuzz suite: malformed input through `volren`",
        "",
        f"Made by `{command}` in {seconds:.0f} s. Failures are the classes {', '.join(FAILURES)}; "
        "`error` is a clean one-line error naming the file or flag, `render` a valid image "
        "(`render-warned` with a one-line warning).",
        "",
        table(results),
        "",
        f"## Failing cases ({len(bad)})",
        "",
    ]
    out += [f"- `{r.case.name}`: {r.outcome}: {r.detail} | `{r.first_line}`" for r in bad] or ["None."]
    return "\n".join(out) + "\n"
