"""The conformance kit on every registered renderer (built-ins and installed plugins), quick."""

from __future__ import annotations

import pytest

from tests.markers import renderer_params
from volren.renderers.registry import registry
from volren.testing import CHECKS, run_check
from volren.testing.runner import renderer_factory

NAMES = registry.names()
#: Checks a renderer is known to fail, and why: the kit is right, the renderer is not (yet). Strict, so
#: a fix shows up as an unexpected pass and the entry goes.
KNOWN_FAILURES: dict[tuple[str, str], str] = {}


@pytest.mark.parametrize("check", CHECKS, ids=[c.name for c in CHECKS])
@pytest.mark.parametrize("name", renderer_params(NAMES))
def test_registered_renderer_conforms(name, check, request):
    if (name, check.name) in KNOWN_FAILURES:
        request.applymarker(pytest.mark.xfail(strict=True, reason=KNOWN_FAILURES[name, check.name]))
    result = run_check(check, renderer_factory(name), quick=True)
    print("\n".join(result.lines()))
    assert result.passed, "\n".join(result.failures())


def test_the_example_plugin_is_registered():
    assert "example" in NAMES, "scripts/setup.sh installs plugins/volren-example"


def test_the_shearwarp_plugin_is_registered():
    assert "shearwarp" in NAMES, "scripts/setup.sh installs plugins/volren-shearwarp"


def test_the_objectorder_plugin_is_registered():
    assert "objectorder" in NAMES, "scripts/setup.sh installs plugins/volren-objectorder"
