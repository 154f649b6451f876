"""Running the conformance checks: each in its own thread with a time limit, one line per result.

Why a thread per check: the contract says a renderer is created, used and released on one thread,
and a check that hangs must fail by itself without stopping the others. Each check makes its own
renderers inside its thread; a check still running at its time limit is reported as failed and
abandoned (its daemon thread cannot hold up the process's exit).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field

from volren.errors import VolrenError
from volren.renderers.base import Renderer
from volren.testing.checks import CHECKS, Check, CheckContext, Measurement

#: Seconds one check may take (numba compilation or a cold GL context included).
DEFAULT_TIME_LIMIT = 300.0

RendererFactory = Callable[[], Renderer]


@dataclass
class CheckResult:
    """What one check measured, or why it could not finish."""

    check: Check
    measurements: list[Measurement] = field(default_factory=list)
    error: str | None = None
    seconds: float = 0.0

    @property
    def passed(self) -> bool:
        return self.error is None and bool(self.measurements) and all(m.passed for m in self.measurements)

    def lines(self) -> list[str]:
        """One line per measurement, and one for an error."""
        out = [m.line() for m in self.measurements]
        if self.error is not None:
            out.append(f"FAIL {self.check.name}: {self.error}")
        elif not self.measurements:
            out.append(
                f"FAIL {self.check.name}: measured nothing (the renderer claims no volume kind the kit has scenes for)"
            )
        return out

    def failures(self) -> list[str]:
        return [line for line in self.lines() if line.startswith("FAIL")]


def one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    if isinstance(exc, VolrenError) or type(exc).__name__ == "ContractError":
        return text
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def renderer_factory(renderer: str | type) -> RendererFactory:
    """A factory of fresh renderers: a registered name, or a renderer class (a plugin's own tests)."""
    if isinstance(renderer, str):
        from volren.renderers.registry import registry

        registry.get(renderer)  # an unknown name fails here, naming the registered ones
        return lambda: registry.create(renderer)
    return renderer


def run_check(check: Check, factory: RendererFactory, quick: bool = False,
              time_limit: float = DEFAULT_TIME_LIMIT) -> CheckResult:  # fmt: skip
    """Run one check in its own thread, waiting at most `time_limit` seconds."""
    result = CheckResult(check)

    def work() -> None:
        ctx = CheckContext(factory, quick)
        try:
            result.measurements = list(check.run(ctx))
        except Exception as exc:  # noqa: BLE001 - a renderer's failure is the check's result
            result.error = one_line(exc)
        finally:
            ctx.close()

    start = time.perf_counter()
    thread = threading.Thread(target=work, name=f"volren-check-{check.name}", daemon=True)
    thread.start()
    thread.join(time_limit)
    result.seconds = time.perf_counter() - start
    if thread.is_alive():
        result.measurements = []
        result.error = f"did not finish within {time_limit:g} s (the renderer hung or is far too slow)"
    return result


def select_checks(names: Iterable[str] | None = None) -> list[Check]:
    """The checks named (all by default); an unknown name is an error listing the valid ones."""
    if names is None:
        return list(CHECKS)
    by_name = {c.name: c for c in CHECKS}
    names = list(names)
    unknown = [n for n in names if n not in by_name]
    if unknown:
        raise VolrenError(f"unknown check(s) {', '.join(unknown)}; choose from {', '.join(by_name)}")
    return [by_name[n] for n in names]


def run_checks(renderer: str | type, quick: bool = False, names: Iterable[str] | None = None,
               time_limit: float = DEFAULT_TIME_LIMIT) -> Iterator[CheckResult]:  # fmt: skip
    """Every selected check on `renderer` (a registered name or a class), one result at a time."""
    factory = renderer_factory(renderer)
    for check in select_checks(names):
        yield run_check(check, factory, quick, time_limit)
