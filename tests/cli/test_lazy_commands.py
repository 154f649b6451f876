"""`volren` imports only the module of the subcommand it runs (`volren.cli.main.COMMANDS`), and its help
reads the same as with every subcommand's module imported."""

from __future__ import annotations

import subprocess
import sys

import pytest

from volren.cli import main as cli_main

HEAVY = ("numpy", "numba", "vtk", "vtkmodules", "pyvista", "matplotlib", "dask", "zarr", "PyQt5", "scipy")
NAMES = [name for name, _, _ in cli_main.COMMANDS]


def help_text(parser, argv: list[str], capsys) -> str:
    with pytest.raises(SystemExit) as exit_info:
        parser.parse_args(argv)
    assert exit_info.value.code == 0
    return capsys.readouterr().out


def test_volren_help_lists_the_commands_as_their_modules_do(capsys):
    full = help_text(cli_main.build_parser(), ["--help"], capsys)
    lazy = help_text(cli_main.build_parser(None, every=False), ["--help"], capsys)
    assert lazy == full
    for name in NAMES:
        assert f"\n    {name}" in full


@pytest.mark.parametrize("name", NAMES)
def test_each_commands_help_is_the_same_with_only_its_module_imported(name, capsys):
    full = help_text(cli_main.build_parser(), [name, "--help"], capsys)
    lazy = help_text(cli_main.build_parser(name, every=False), [name, "--help"], capsys)
    assert lazy == full and f"volren {name}" in lazy


@pytest.mark.parametrize("argv, name", [(["render", "in.vti"], "render"), (["--traceback", "movie", "-o", "x"], "movie"),
                                        (["--help"], None), ([], None), (["nosuch", "--help"], "nosuch")])  # fmt: skip
def test_the_command_is_the_first_word_that_is_not_an_option(argv, name):
    assert cli_main.command_named(argv) == name


def loaded_after(code: str) -> list[str]:
    """The heavy packages in sys.modules after `code` ran (its own output left out)."""
    probe = f"{code}\nimport sys\nprint('loaded:', *(m for m in {HEAVY!r} if m in sys.modules))"
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return done.stdout.splitlines()[-1].split()[1:]


def test_volren_help_and_version_load_no_heavy_package():
    for argv in (["--help"], ["--version"]):
        code = f"from volren.cli.main import main\ntry:\n    main({argv!r})\nexcept SystemExit:\n    pass"
        assert loaded_after(code) == []


def test_a_command_does_not_import_the_other_commands():
    code = "from volren.cli.main import main\ntry:\n    main(['prepare', '--help'])\nexcept SystemExit:\n    pass"
    probe = f"{code}\nimport sys\nprint(*sorted(m for m in sys.modules if m.startswith('volren.')))"
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    loaded = done.stdout.splitlines()[-1].split()
    assert "volren.cli.prepare_cmd" in loaded
    others = [f"volren.cli.{module}" for _, module, _ in cli_main.COMMANDS if module != "prepare_cmd"]
    assert [m for m in others if m in loaded] == []
    assert "volren.bench.datasets" not in loaded and "volren.draw" not in loaded


def freeze_count_after(call: str) -> int:
    """gc.get_freeze_count() in a new interpreter after `call` (a call of main) ran."""
    code = (f"import gc, sys\nfrom volren.cli.main import main\nsys.argv = ['volren', '--version']\n"
            f"try:\n    {call}\nexcept SystemExit:\n    pass\nprint(gc.get_freeze_count())")  # fmt: skip
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return int(done.stdout.splitlines()[-1])


def test_the_program_leaves_its_objects_to_the_os_and_a_caller_keeps_its_collector():
    assert freeze_count_after("main()") > 0
    assert freeze_count_after("main(['--version'])") == 0


def test_a_render_of_a_grid_or_a_tetrahedral_mesh_imports_no_pyvista(tmp_path):
    """Image data and unstructured grids are read through VTK's own API: PyVista's import (a quarter
    of a second) is paid only where other cells are split or another kind of dataset needs it."""
    from volren.samples import sample_paths

    for sample, expect in (("phantom_ct", False), ("hollow_cylinder", False)):
        volume, tf = sample_paths(sample)
        argv = [
            "render",
            str(volume),
            "--tf",
            str(tf),
            "--size",
            "32x32",
            "-o",
            str(tmp_path / f"{sample}.png"),
        ]
        code = (f"import os\nos.environ['VOLREN_READ_IN_PROCESS'] = '1'  # the load in this process, not a child\n"
                f"from volren.cli.main import main\nassert main({argv!r}) == 0")  # fmt: skip
        assert ("pyvista" in loaded_after(code)) is expect, sample
        assert (tmp_path / f"{sample}.png").is_file()
