"""Every renderer takes the optical model's shared pieces (the no-shading threshold, the lighting, the
sample placement) from `volren.kernels`, so that one change there changes them all."""

from __future__ import annotations

import ast
import importlib
import os
import pkgutil
from pathlib import Path

import pytest

from volren.kernels import sample_placement, shading

REPO = Path(__file__).resolve().parents[2]
#: the shared pieces, by name
SHARED = {
    name: getattr(module, name)
    for module, names in (
        (shading, ("GRADIENT_EPS", "gradient_threshold", "blinn_phong_factors", "headlight_half_vector")),
        (sample_placement, ("ray_segments", "ray_segment", "segment_length", "pixel_phases")),
    )
    for name in names
}
RENDERER_PACKAGES = ("volren.renderers", "volren_objectorder", "volren_shearwarp", "volren_example")


def renderer_modules() -> list[str]:
    names = []
    for package in RENDERER_PACKAGES:
        root = importlib.import_module(package)
        names += [package] + [m.name for m in pkgutil.walk_packages(root.__path__, package + ".")]
    return names


def source_files() -> list[Path]:
    paths = [*(REPO / "volren").rglob("*.py"), *(REPO / "plugins").glob("*/volren_*/**/*.py")]
    return [p for p in paths if p.parent != REPO / "volren" / "kernels"]


def test_no_module_outside_the_kernels_defines_a_shared_piece():
    """A copy under the same name (the threshold was defined in four modules)."""
    found = []
    for path in source_files():
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            targets = []
            if isinstance(node, ast.Assign):
                targets = [t.id for t in node.targets if isinstance(t, ast.Name)]
            elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
                targets = [node.target.id]
            elif isinstance(node, ast.FunctionDef):
                targets = [node.name]
            found += [f"{path.relative_to(REPO)}: {name}" for name in targets if name in SHARED]
    assert found == []


@pytest.mark.parametrize("module_name", renderer_modules())
def test_renderer_modules_hold_the_kernels_own_objects(module_name):
    module = importlib.import_module(module_name)
    for name, shared in SHARED.items():
        if hasattr(module, name):
            assert getattr(module, name) is shared, f"{module_name}.{name} is not the kernel's"


@pytest.mark.parametrize("package", ["volren.renderers.raycast", "volren.renderers.tetra", "volren_objectorder",
                                     "volren_shearwarp"])  # fmt: skip
def test_renderers_calling_the_kernels_drop_their_stale_numba_cache(package):
    """numba checks only a kernel's own source: after an edit to `volren.kernels`, a renderer must not
    keep running the copy it inlined from its cache."""
    module = importlib.import_module(package)
    stale = Path(module.__file__).parent / "__pycache__" / "stale-probe.nbi"
    stale.parent.mkdir(exist_ok=True)
    stale.touch()
    os.utime(stale, (0, 0))
    try:
        importlib.reload(module)
        assert not stale.exists()
    finally:
        stale.unlink(missing_ok=True)
