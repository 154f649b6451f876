"""Wall time of a command's stages (`volren render --timings`): where a one-shot render spends it.

Why: a one-shot render's wall time is mostly not the frame (imports, loading, mesh
preparation, tables); the stages show which to cut. Start-up is counted from the process's start
(Linux: /proc) to the command's first line, so it covers the interpreter and the imports.
"""

from __future__ import annotations

import os
import time
from collections.abc import Iterator, Mapping
from contextlib import contextmanager


def process_age_s() -> float | None:
    """Seconds since this process started, or None where /proc does not say (not Linux)."""
    try:
        with open(f"/proc/{os.getpid()}/stat", encoding="ascii") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        with open("/proc/uptime", encoding="ascii") as f:
            uptime = float(f.read().split()[0])
        return max(uptime - int(fields[19]) / os.sysconf("SC_CLK_TCK"), 0.0)
    except (OSError, ValueError, IndexError):
        return None


class StageClock:
    """Named stages in the order they ran, each with its wall seconds."""

    def __init__(self) -> None:
        self.stages: list[tuple[str, float]] = []
        age = process_age_s()
        if age is not None:
            self.stages.append(("start-up", age))
        self.details: dict[str, float] = {}  # parts of the frame the renderer timed itself (seconds)

    @contextmanager
    def stage(self, name: str) -> Iterator[None]:
        start = time.perf_counter()
        try:
            yield
        finally:
            self.stages.append((name, time.perf_counter() - start))

    def note_counters(self, counters: Mapping[str, float]) -> None:
        """Keep the renderer's own timings of its first frame (counters ending in `_ms`)."""
        self.details.update(
            {k.removesuffix("_ms"): v / 1000.0 for k, v in counters.items() if k.endswith("_ms") and v > 0}
        )

    def line(self) -> str:
        parts = []
        for name, seconds in self.stages:
            text = f"{name} {seconds:.2f} s"
            if name == "frame" and self.details:
                text += " (" + ", ".join(f"{k} {v:.2f} s" for k, v in self.details.items()) + ")"
            parts.append(text)
        total = sum(seconds for _, seconds in self.stages)
        return f"timings: {', '.join(parts)}; total {total:.2f} s"
