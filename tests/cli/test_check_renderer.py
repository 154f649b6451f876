"""`volren check-renderer`: exit 0 when conformant, one FAIL line per failed measurement and exit 1
otherwise, one line naming the registered renderers for an unknown name."""

from __future__ import annotations

from tests.renderers.protocol_renderer import PlainRenderer
from volren.cli.main import main
from volren.renderers.registry import registry


def test_an_unknown_renderer_is_one_line_naming_the_registered_ones(capsys):
    assert main(["check-renderer", "nosuch"]) == 1
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "unknown renderer 'nosuch'" in err
    for name in ("vtk", "reference", "slicer", "tetra"):
        assert name in err


def test_a_conformant_renderer_exits_0(capsys):
    assert main(["check-renderer", "example", "--quick", "--check", "box", "--check", "point"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert all(line.startswith("PASS") for line in out[:-1]) and "conformant" in out[-1]
    assert any("box [uniform, perspective] RMSE" in line and "bound <= 0.05" in line for line in out)


def test_a_failing_renderer_prints_its_numbers_and_exits_1(capsys):
    registry.register("plain", PlainRenderer, replace=True)
    try:
        code = main(["check-renderer", "plain", "--check", "empty", "--check", "box", "--time-limit", "60"])
    finally:
        registry.unregister("plain")
    assert code == 1
    out = capsys.readouterr().out.splitlines()
    fails = [line for line in out if line.startswith("FAIL")]
    assert fails and all("bound" in line for line in fails)
    assert any(line.startswith("FAIL empty [uniform] max abs 0.5") for line in fails)
    assert "2 of 2 checks failed" in out[-1]


def test_an_unknown_check_is_named(capsys):
    assert main(["check-renderer", "example", "--check", "nosuch"]) == 1
    assert "unknown check(s) nosuch; choose from output, empty" in capsys.readouterr().err
