"""tests/session_policy.py: a skip fails unless its reason is on the allow-list (checked on a
throw-away test folder in a subprocess), and the caches of this session are its own."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

from tests import session_policy
from tests.session_policy import NO_GPU, SESSION_CACHE, SHARED_MISSING

REPO = Path(__file__).resolve().parents[1]

SKIPPING = f'''
import pytest

def test_shared_missing():
    pytest.skip("{SHARED_MISSING}: no datasets at ../shared/data")

def test_no_gpu():
    pytest.skip("{NO_GPU}: llvmpipe is not a hardware GPU")

def test_missing_package():
    pytest.importorskip("no_such_package_volren")

@pytest.mark.skipif(True, reason="volren.io is not available yet")
def test_marked():
    pass

@pytest.fixture
def broken_renderer():
    pytest.skip("the vtk renderer cannot render here")

def test_fixture_skip(broken_renderer):
    pass

def test_expected_failure():
    pytest.xfail("known")

def test_passes():
    pass
'''

MODULE_SKIP = """
import pytest

pytest.importorskip("no_such_package_volren")

def test_never_runs():
    pass
"""


def test_only_allowed_skips_stay_skips(tmp_path):
    (tmp_path / "test_skipping.py").write_text(SKIPPING)
    (tmp_path / "test_module_skip.py").write_text(MODULE_SKIP)
    (tmp_path / "pytest.ini").write_text("[pytest]\n")
    cmd = [sys.executable, "-m", "pytest", "-p", "tests.session_policy", "-p", "no:cacheprovider", "-rA",
           "--continue-on-collection-errors",
           "-c", str(tmp_path / "pytest.ini"), "--rootdir", str(tmp_path), str(tmp_path)]  # fmt: skip
    result = subprocess.run(cmd, capture_output=True, text=True, timeout=120, cwd=REPO)
    out = result.stdout
    assert result.returncode == 1, out
    summary = out.strip().splitlines()[-1]
    counts = {word: int(n) for n, word in re.findall(r"(\d+) (\w+)", summary)}
    # failed: importorskip in the test; errors: skipif and the fixture's skip (both at setup) and
    # the module's importorskip (collection)
    assert counts == {"failed": 1, "passed": 1, "skipped": 2, "xfailed": 1, "errors": 3}, summary
    for name in ("test_missing_package", "test_marked", "test_fixture_skip"):
        assert re.search(rf"(FAILED|ERROR) .*{name}", out), name
    assert re.search(r"ERROR .*test_module_skip.py", out)
    assert "skipped for a reason that is not allowed: volren.io is not available yet" in out
    assert "could not import 'no_such_package_volren'" in out


def test_reasons_on_the_list():
    assert session_policy.allowed(f"{SHARED_MISSING}: scene x.json not found")
    assert session_policy.allowed(f"{NO_GPU}: needs OpenGL 4.3 on a hardware GPU")
    assert not session_policy.allowed("PyQt5 is not installed")
    assert not session_policy.allowed("xvfb-run is not on PATH")


def test_caches_are_this_sessions_own():
    from volren.model import tet_mesh
    from volren.testing import reference_images

    home_cache = Path.home() / ".cache"
    for folder in (tet_mesh.cache_dir(), reference_images.cache_folder(), Path(os.environ["XDG_CACHE_HOME"])):
        assert SESSION_CACHE in folder.parents, folder
        assert home_cache not in folder.parents, folder
    assert SESSION_CACHE.is_dir()


def test_subprocesses_inherit_the_session_caches():
    code = "from volren.model import tet_mesh; print(tet_mesh.cache_dir())"
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60, cwd=REPO
    )
    assert result.returncode == 0, result.stderr
    assert Path(result.stdout.strip()) == tet_mesh_dir()


def tet_mesh_dir() -> Path:
    from volren.model import tet_mesh

    return tet_mesh.cache_dir()
