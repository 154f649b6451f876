"""Rules for every test session (loaded by the repository's root conftest.py, so they cover tests/
and plugins/ alike):

- **Skips are failures unless their reason is on a short list.** A test may skip only because
  the real datasets (``../shared``) are not there or because it needs a hardware GPU; any other
  skip (a missing package, a renderer that cannot draw, a tool not on PATH) means the machine is
  not set up the way CI is, and hiding that is how failures went unnoticed. Allowed reasons start
  with one of `ALLOWED_SKIP_PREFIXES`: use `SHARED_MISSING` / `NO_GPU` in the reason.
- **Caches are per session** (per worker under pytest-xdist). volren's on-disk caches (prepared meshes, reference images, the
  generated samples) and everything else that follows ``$XDG_CACHE_HOME`` point into a temporary
  folder made when this module is imported (before any test runs and before volren reads the
  variables, which it does at each use), so a test can neither pass on stale data from an earlier
  run nor leave any behind in ``~/.cache``. Subprocesses inherit the variables. numba's JIT cache
  stays where numba keeps it (``__pycache__`` beside the sources): it is keyed by source file and
  timestamp, `volren.numba_cache.drop_stale_cache` discards it when any module a kernel calls into
  changes, and recompiling every kernel each session would add minutes.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

import pytest

#: The start of a skip reason for a test that needs the real datasets in ../shared.
SHARED_MISSING = "shared data missing"
#: The start of a skip reason for a test that needs a hardware GPU (OpenGL 4.3 on real hardware).
NO_GPU = "no GPU"
ALLOWED_SKIP_PREFIXES = (SHARED_MISSING, NO_GPU)

#: The cache variables set for the session: volren's own, then the XDG default the rest follow.
CACHE_VARIABLES = {
    "VOLREN_MESH_CACHE": "meshes",  # volren.model.tet_mesh.cache_dir
    "VOLREN_REFERENCE_CACHE": "reference",  # volren.testing.reference_images.cache_folder
    "XDG_CACHE_HOME": "xdg",  # volren.samples' generated copies; matplotlib, fontconfig, Mesa, pip
}

SESSION_CACHE = Path(tempfile.mkdtemp(prefix="volren-test-cache-"))
for _name, _folder in CACHE_VARIABLES.items():
    os.environ[_name] = str(SESSION_CACHE / _folder)


def pytest_unconfigure(config: pytest.Config) -> None:
    shutil.rmtree(SESSION_CACHE, ignore_errors=True)


def skip_reason(report: pytest.TestReport | pytest.CollectReport) -> str:
    longrepr = report.longrepr
    if isinstance(longrepr, tuple) and len(longrepr) == 3:
        reason = str(longrepr[2])
    else:
        reason = str(longrepr)
    return reason.removeprefix("Skipped: ")


def allowed(reason: str) -> bool:
    return reason.startswith(ALLOWED_SKIP_PREFIXES)


def _police(report: pytest.TestReport | pytest.CollectReport) -> None:
    if not report.skipped or hasattr(report, "wasxfail"):
        return
    reason = skip_reason(report)
    if allowed(reason):
        return
    report.outcome = "failed"
    report.longrepr = (
        f"skipped for a reason that is not allowed: {reason}\n"
        f"(a test may skip only when its reason starts with one of {ALLOWED_SKIP_PREFIXES}; "
        "see tests/session_policy.py)"
    )


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo):
    outcome = yield
    _police(outcome.get_result())


@pytest.hookimpl(hookwrapper=True)
def pytest_make_collect_report(collector: pytest.Collector):
    outcome = yield
    _police(outcome.get_result())
