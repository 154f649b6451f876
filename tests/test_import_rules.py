"""DESIGN.md's import rules: app, cli -> renderers, io -> model; model pure numpy (numba only in
model.preintegration, whose kernels the pre-integration issue asks for in numpy/numba); no Qt in
renderers, the CLI or the app's core (volren.app.core); no matplotlib in the app; io and renderers
independent. Checked statically (every import statement) and at run time (what `import volren`,
the app's core and the CLI actually load)."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "volren"
HEAVY = ("vtk", "vtkmodules", "pyvista", "pyvistaqt", "moderngl", "PyQt5", "numba", "matplotlib")


def imported_modules(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module)
    return names


def imports_of(subpackage: str) -> dict[Path, set[str]]:
    return {p: imported_modules(p) for p in (PACKAGE / subpackage).rglob("*.py")}


def offending(subpackage: str, forbidden: tuple[str, ...], allowed: dict[str, tuple[str, ...]] | None = None) -> list[str]:
    """Imports of `forbidden` modules; `allowed` maps a sub-folder to modules it may import anyway."""
    allowed = allowed or {}

    def permitted(path: Path, name: str) -> bool:
        rel = path.relative_to(PACKAGE / subpackage).as_posix()
        return any(rel.startswith(folder + "/") and name.split(".")[0] in mods for folder, mods in allowed.items())

    return [
        f"{path.relative_to(PACKAGE)} imports {name}"
        for path, names in imports_of(subpackage).items()
        for name in names
        if any(name == f or name.startswith(f + ".") for f in forbidden) and not permitted(path, name)
    ]


RENDERER_PACKAGES = sorted(p.parent.name for p in (PACKAGE / "renderers").glob("*/__init__.py"))
#: Who may import a renderer's package (its public names, never its modules) from outside it: the
#: benchmarks take the reference's one-segment integral as the truth of pre-integration tables.
PUBLIC_RENDERER_USERS = {"reference": ("bench/",)}


def test_a_renderer_is_imported_only_by_itself():
    """Renderers share code through `volren.kernels` and the model, never through each other's
    modules, so the reference that judges them shares no integrator with them. The registry
    names renderers by entry-point strings, not imports; tests may import anything."""
    assert len(RENDERER_PACKAGES) >= 4
    found = []
    for path in PACKAGE.rglob("*.py"):
        rel = path.relative_to(PACKAGE).as_posix()
        for name in imported_modules(path):
            for renderer in RENDERER_PACKAGES:
                package = f"volren.renderers.{renderer}"
                if name != package and not name.startswith(package + "."):
                    continue
                if rel.startswith(f"renderers/{renderer}/"):
                    continue
                public = name == package and rel.startswith(PUBLIC_RENDERER_USERS.get(renderer, ()))
                if not public:
                    found.append(f"{rel} imports {name}")
    assert found == []


def test_kernels_need_only_the_model_and_the_contract():
    # typing: the kernels' parameter bundles are typing.NamedTuples (numba types them as named tuples)
    allowed = ("numpy", "numba", "math", "collections", "contextlib", "pathlib", "typing", "__future__",
               "volren.model", "volren.errors", "volren.renderers.base", "volren.numba_cache")
    found = [
        f"{path.relative_to(PACKAGE)} imports {name}"
        for path, names in imports_of("kernels").items()
        for name in names
        if not any(name == a or name.startswith(a + ".") for a in allowed)
    ]
    assert found == []


PLUGINS = PACKAGE.parent / "plugins"
#: What a plugin may import of volren: what a third party builds on (the model, the renderer contract
#: and its error type) and the kernels that hold the optical model every renderer shares.
PLUGIN_ALLOWED = ("volren.model", "volren.kernels", "volren.renderers.base", "volren.errors")


def test_plugins_import_only_the_contract_the_model_and_the_kernels():
    found = []
    paths = sorted(PLUGINS.glob("*/volren_*/**/*.py"))
    for path in paths:
        for name in imported_modules(path):
            ours = name == "volren" or name.startswith("volren.")
            if ours and not any(name == a or name.startswith(a + ".") for a in PLUGIN_ALLOWED):
                found.append(f"{path.relative_to(PLUGINS)} imports {name}")
    assert len(paths) >= 10
    assert found == []


@pytest.mark.parametrize(
    "subpackage, forbidden",
    [
        ("model", HEAVY + ("volren.io", "volren.renderers", "volren.app", "volren.cli", "volren.kernels")),
        ("renderers", ("PyQt5", "pyvistaqt", "pyvista", "volren.io", "volren.app", "volren.cli")),
        ("io", ("PyQt5", "pyvistaqt", "moderngl", "volren.renderers", "volren.app", "volren.cli")),
        ("cli", ("PyQt5", "pyvistaqt", "volren.app")),
        # the app's core is its Qt-free logic: no Qt, and none of the app's Qt parts
        ("app/core", ("PyQt5", "pyvistaqt", "matplotlib", "volren.cli", "volren.app.files", "volren.app.main",
                      "volren.app.panels", "volren.app.rendering", "volren.app.tf_editor", "volren.app.window")),
        # matplotlib is the `bench` extra: the app's colour maps are data (app/core/colormap_presets.json)
        ("app", ("matplotlib",)),
        # the kit judges renderers through the public contract only: no renderer's internals
        ("testing", HEAVY + ("vtkmodules", "volren.io", "volren.app", "volren.cli", "volren.bench",
                             "volren.renderers.reference", "volren.renderers.slicer", "volren.renderers.tetra",
                             "volren.renderers.vtk_mappers")),  # fmt: skip
    ],
)
def test_static_import_rules(subpackage, forbidden):
    allowed = {"preintegration": ("numba",)} if subpackage == "model" else None
    assert offending(subpackage, forbidden, allowed) == []


def test_numba_in_the_model_stays_in_preintegration():
    """The exception is narrow: numba anywhere else in the model is still reported."""
    assert offending("model", ("numba",), {"preintegration": ("numba",)}) == []
    found = offending("model", ("numba",))
    assert found and all(line.startswith("model/preintegration/") for line in found)


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
