"""What installing volren brings in: Qt and matplotlib only through extras (`app`, `bench`), a
`volren render` that loads neither (and works where they are not installed), `volren view` and
the plots saying in one line what to install, pins for every dependency, one version string and
a licence that matches pyproject.toml."""

from __future__ import annotations

import importlib.metadata
import json
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

import volren
from tests.markers import renderer_params

REPO = Path(__file__).resolve().parents[1]
PROJECT = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
SAMPLE = REPO / "data_samples" / "marschner_lobb.vti"
SAMPLE_TF = REPO / "data_samples" / "marschner_lobb.tf.json"
#: Optional packages and the extra that brings each.
OPTIONAL = {
    "pyqt5": "app",
    "matplotlib": "bench",
    "vispy": "bench",
    "pyopengl": "bench",
    "imageio": "movie",
    "imageio-ffmpeg": "movie",
    "zarr": "zarr",
    "distributed": "cluster",
}


def names(requirements: list[str]) -> set[str]:
    return {canonicalize_name(Requirement(r).name) for r in requirements}


def installs_of_this_checkout() -> list[importlib.metadata.Distribution]:
    """The installed metadata built from this checkout: an install whose direct_url.json points
    here, or the egg-info that an editable install leaves in the source tree."""
    found = []
    for dist in importlib.metadata.distributions(name="volren"):
        text = dist.read_text("direct_url.json")
        url = json.loads(text).get("url", "").rstrip("/") if text else ""
        if url == REPO.as_uri() or Path(dist.locate_file("")).resolve() == REPO:
            found.append(dist)
    return found


def test_qt_and_matplotlib_are_only_in_extras():
    assert names(PROJECT["dependencies"]).isdisjoint(OPTIONAL)
    extras = PROJECT["optional-dependencies"]
    for package, extra in OPTIONAL.items():
        assert package in names(extras[extra]), (package, extra)
    assert {"pytest", "pytest-qt", "hypothesis", "ruff"} <= names(extras["test"])


def test_the_installed_metadata_says_the_same():
    """The metadata pip reads, where it was built from this checkout (as in CI's .venv; a session
    that imports this tree against another checkout's install has only the pyproject check)."""
    for dist in installs_of_this_checkout():
        for line in dist.requires or []:
            req = Requirement(line)
            name = canonicalize_name(req.name)
            if name in OPTIONAL:
                assert req.marker is not None and req.marker.evaluate({"extra": OPTIONAL[name]}), line
                assert not req.marker.evaluate({"extra": ""}), line


def test_every_dependency_is_pinned_within_its_bounds():
    pins = {}
    for line in (REPO / "constraints.txt").read_text().splitlines():
        line = line.split("#", 1)[0].strip()
        if line:
            req = Requirement(line)
            (spec,) = req.specifier
            assert spec.operator == "==", line
            pins[canonicalize_name(req.name)] = spec.version
    declared = PROJECT["dependencies"] + [
        r for group in PROJECT["optional-dependencies"].values() for r in group
    ]
    for line in declared:
        req = Requirement(line)
        name = canonicalize_name(req.name)
        assert name in pins, f"{req.name} is not pinned in constraints.txt"
        assert req.specifier.contains(pins[name]), f"{req.name}: pinned {pins[name]} outside {req.specifier}"


def run_volren(*args: str, block: tuple[str, ...] = ()) -> subprocess.CompletedProcess:
    """`volren ARGS` in a fresh interpreter; `block`: top-level packages made unimportable (as if
    not installed). Prints the optional packages loaded by the end, as its last stdout line."""
    code = (
        "import importlib.abc, sys\n"
        f"BLOCKED = {set(block)!r}\n"
        "class Block(importlib.abc.MetaPathFinder):\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name.split('.')[0] in BLOCKED:\n"
        "            raise ModuleNotFoundError(f'No module named {name!r}', name=name)\n"
        "sys.meta_path.insert(0, Block())\n"
        "from volren.cli.main import main\n"
        "code = main(sys.argv[1:])\n"
        "print('loaded:', *sorted(m for m in ('PyQt5', 'matplotlib') if m in sys.modules))\n"
        "sys.exit(code)\n"
    )
    return subprocess.run(
        [sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=300, cwd=REPO
    )


@pytest.mark.usefixtures("opengl")
@pytest.mark.parametrize("renderer", renderer_params(["vtk", "slicer"]))
def test_volren_render_loads_neither_qt_nor_matplotlib(tmp_path, renderer):
    out = tmp_path / "out.png"
    result = run_volren("render", str(SAMPLE), "--tf", str(SAMPLE_TF), "-o", str(out), "--size", "16",
                        "--renderer", renderer)  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert out.is_file()
    assert result.stdout.splitlines()[-1] == "loaded:"


@pytest.mark.usefixtures("opengl")
def test_volren_render_works_without_them_installed(tmp_path):
    out = tmp_path / "out.png"
    result = run_volren("render", str(SAMPLE), "-o", str(out), "--size", "16", block=("PyQt5", "matplotlib"))
    assert result.returncode == 0, result.stderr
    assert out.is_file()


@pytest.mark.parametrize(
    "args, blocked, extra",
    [
        (["view"], "PyQt5", "app"),
        (["bench", "app"], "PyQt5", "app"),
        (["bench", "run", "--quick", "--datasets", "marschner_lobb"], "matplotlib", "bench"),
    ],
)
def test_a_missing_extra_is_one_line_naming_it(args, blocked, extra):
    result = run_volren(*args, block=(blocked,))
    assert result.returncode == 1
    (line,) = result.stderr.strip().splitlines()
    assert line.startswith("volren: error: ") and blocked in line and f"pip install 'volren[{extra}]'" in line


def test_a_movie_without_its_extra_is_one_line_naming_it(tmp_path):
    for movie, blocked in (("m.gif", "imageio"), ("m.mp4", "imageio_ffmpeg")):
        result = run_volren("movie", str(SAMPLE), "-o", str(tmp_path / movie), block=(blocked,))
        assert result.returncode == 1
        (line,) = result.stderr.strip().splitlines()
        assert line.startswith("volren: error: ") and blocked.replace("_", "-") in line, line
        assert "pip install 'volren[movie]'" in line
    assert not list(tmp_path.iterdir())


def test_ome_zarr_without_its_extra_is_one_line_naming_it(tmp_path):
    result = run_volren("convert", str(SAMPLE), str(tmp_path / "x.zarr"), block=("zarr",))
    assert result.returncode == 1
    (line,) = result.stderr.strip().splitlines()
    assert line.startswith("volren: error: ") and "zarr" in line and "pip install 'volren[zarr]'" in line
    assert not list(tmp_path.iterdir())


def test_a_cluster_without_its_extra_is_one_line_naming_it(tmp_path):
    result = run_volren("render", str(SAMPLE), "--cluster", "local:1", "-o", str(tmp_path / "x.png"),
                        block=("distributed",))  # fmt: skip
    assert result.returncode == 1
    (line,) = result.stderr.strip().splitlines()
    assert line.startswith("volren: error: ") and "pip install 'volren[cluster]'" in line, line
    assert not list(tmp_path.iterdir())


def test_one_version_string():
    assert volren.__version__ == PROJECT["version"] == importlib.metadata.version("volren")
    result = subprocess.run([sys.executable, "-m", "volren.cli.main", "--version"], capture_output=True,
                            text=True, timeout=60, cwd=REPO)  # fmt: skip
    assert result.stdout.strip() == f"volren {PROJECT['version']}"
    copies = [
        p for p in (REPO / "volren").rglob("*.py") if re.search(r"__version__\s*=\s*['\"]", p.read_text())
    ]
    assert copies == []


def test_the_licence_matches_pyproject():
    assert PROJECT["license"] == "BSD-3-Clause"
    text = (REPO / "LICENSE").read_text()
    assert text.startswith("BSD 3-Clause License")
    assert "the volren developers" in text.splitlines()[2]
    assert "Neither the name of the copyright holder nor the names of its" in text


def test_every_renderers_measured_levels_are_package_data_of_the_distribution_that_installs_it():
    """`auto` reads each renderer's quality_levels.json from the renderer's installed package: the
    core's pyproject ships the built-ins' (`*.json` under every volren package), each plugin's
    pyproject its own."""
    from fnmatch import fnmatch

    from volren.quality import LEVELS_FILE

    def shipped(pyproject: Path, package: str) -> bool:
        tool = tomllib.loads(pyproject.read_text())["tool"]["setuptools"]
        patterns = [p for key in ("*", package) for p in tool.get("package-data", {}).get(key, [])]
        return any(fnmatch(LEVELS_FILE, p) for p in patterns)

    found = sorted(REPO.glob(f"volren/**/{LEVELS_FILE}")) + sorted(REPO.glob(f"plugins/*/*/{LEVELS_FILE}"))
    assert {p.parent.name for p in found} >= {"raycast", "slicer", "tetra", "vtk_mappers", "volren_shearwarp",
                                              "volren_objectorder"}  # fmt: skip
    for path in found:
        package_dir = path.parent
        project = next(d for d in package_dir.parents if (d / "pyproject.toml").is_file())
        package = ".".join(package_dir.relative_to(project).parts)
        assert (package_dir / "__init__.py").is_file(), path  # a package, so package data
        assert shipped(project / "pyproject.toml", package), path
    for dist in installs_of_this_checkout():  # the installed file list, where built from this checkout
        files = [str(f) for f in dist.files or []]
        if any(
            f.startswith("volren/") and f.endswith(".py") for f in files
        ):  # not an editable install's finder
            assert any(f.endswith(f"renderers/raycast/{LEVELS_FILE}") for f in files), dist
