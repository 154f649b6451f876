"""The kit inside a plugin's own pytest suite: one parametrized test per check.

pytest is imported only when a test module asks for the kit, so installing volren does not need it.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

from volren.testing.runner import DEFAULT_TIME_LIMIT, renderer_factory, run_check, select_checks


def conformance_test(renderer: str | type, quick: bool = False, checks: Iterable[str] | None = None,
                     time_limit: float = DEFAULT_TIME_LIMIT) -> Callable[[str], None]:  # fmt: skip
    """A pytest test function, parametrized over the checks, for `renderer` (a registered name or a
    class). Assign it to a module-level name starting with ``test_``. A failing check fails its
    test with the check's FAIL lines (measured number and bound), without a traceback."""
    import pytest

    selected = select_checks(checks)

    @pytest.mark.parametrize("check", selected, ids=[c.name for c in selected])
    def test_conformance(check) -> None:
        result = run_check(check, renderer_factory(renderer), quick, time_limit)
        print("\n".join(result.lines()))
        if not result.passed:
            pytest.fail("\n".join(result.failures()), pytrace=False)

    return test_conformance
