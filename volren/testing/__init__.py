"""The conformance kit and the error metric: what a renderer author runs to learn whether their
renderer draws what the contract (docs/renderer-contract.md) says.

From the command line: ``volren check-renderer NAME [--quick]``. From a plugin's pytest suite::

    from volren.testing import conformance_test
    test_conformance = conformance_test(MyRenderer, quick=True)   # one test per check

The checks compare against closed forms (`oracles`) on small scenes (`scenes`), so they need no
reference run; `metrics.image_error` is DESIGN.md's error metric. Where an exact oracle does
not exist, `reference_images` gives the `reference` renderer's image of a scene (through the
public API), cached on disk by a hash of everything that determines it.
"""

from volren.testing.checks import CHECKS, Check, CheckContext, ContractError, Measurement
from volren.testing.metrics import ImageError, image_error
from volren.testing.pytest_support import conformance_test
from volren.testing.runner import CheckResult, run_check, run_checks, select_checks

__all__ = [
    "CHECKS", "Check", "CheckContext", "CheckResult", "ContractError", "ImageError", "Measurement",
    "conformance_test", "image_error", "run_check", "run_checks", "select_checks",
]  # fmt: skip
