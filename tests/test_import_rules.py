"""The import rules at run time: what `import volren`, the model, the app's core and the CLI
actually load (lazy imports included). The static rules (the layers, no import circles, what
plugins, the model, renderers, readers, the app's core and the conformance kit may import) are
import-linter contracts in pyproject.toml, checked by `lint-imports` in CI (.ci/run); the test
below keeps those contracts in step with the renderer packages and the plugins on disk."""

from __future__ import annotations

import subprocess
import sys
import tomllib
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PACKAGE = REPO / "volren"
HEAVY = ("vtk", "vtkmodules", "pyvista", "pyvistaqt", "moderngl", "PyQt5", "numba", "matplotlib")
CONTRACTS = {
    c["name"]: c
    for c in tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["importlinter"]["contracts"]
}


def contract(type_: str, words: str) -> dict:
    (found,) = [c for name, c in CONTRACTS.items() if c["type"] == type_ and words in name]
    return found


def test_the_contracts_name_every_renderer_package_and_every_plugin():
    """A new renderer package or plugin is covered by the rules only once a contract names it."""
    renderers = {f"volren.renderers.{p.parent.name}" for p in (PACKAGE / "renderers").glob("*/__init__.py")}
    plugins = {p.parent.name for p in REPO.glob("plugins/*/volren_*/__init__.py")}
    assert len(renderers) >= 4 and len(plugins) >= 3
    assert set(contract("independence", "renderers share no code")["modules"]) == renderers
    assert set(contract("forbidden", "renderer's modules")["forbidden_modules"]) == renderers
    assert set(contract("forbidden", "A plugin imports only")["source_modules"]) == plugins
    assert renderers <= set(contract("forbidden", "A plugin imports only")["forbidden_modules"])
    roots = set(tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["importlinter"]["root_packages"])
    assert roots == {"volren", "benchmarks"} | plugins
    assert set(contract("acyclic_siblings", "circles")["ancestors"]) == roots


def loaded_after(code: str) -> list[str]:
    probe = f"{code}\nimport sys\nprint(' '.join(m for m in {HEAVY!r} if m in sys.modules))"
    result = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    return result.stdout.split()


def test_importing_volren_and_the_model_is_light():
    assert loaded_after("import volren, volren.model, volren.model.scene, volren.errors") == []


def test_preintegration_loads_numba_and_nothing_heavier():
    assert loaded_after("import volren.model.preintegration") == ["numba"]


def test_the_app_core_loads_no_qt():
    """Importing every core module (and so everything they import) loads neither Qt nor
    matplotlib; nor does `import volren.app`."""
    core = sorted(f"volren.app.core.{p.stem}" for p in (PACKAGE / "app" / "core").glob("*.py"))
    assert "volren.app.core.state" in core
    loaded = loaded_after(f"import volren.app, {', '.join(core)}")
    assert "PyQt5" not in loaded and "pyvistaqt" not in loaded and "matplotlib" not in loaded


def test_importing_the_app_package_loads_no_qt():
    assert loaded_after("import volren.app") == []


def test_the_cli_runs_without_qt():
    loaded = loaded_after("from volren.cli.main import main\nmain(['renderers'])")
    assert "PyQt5" not in loaded and "pyvistaqt" not in loaded
