"""Everything `volren` says on stderr is one line starting with `volren: `, once per message:
warnings from numpy and other libraries, log records, and VTK output (issue 25, item 5)."""

from __future__ import annotations

import io
import json
import logging
import os
import subprocess
import sys
import warnings
from collections import Counter

import numpy as np
import pytest

from volren.cli.messages import LinePrinter, fold, one_line_messages
from volren.errors import VolrenWarning


def test_fold_puts_any_text_on_one_line():
    assert fold("a\n  b\tc\r\n\nd ") == "a b c d"


def test_the_printer_folds_and_prints_each_message_once():
    out = io.StringIO()
    printer = LinePrinter(out)
    printer.warn("two\nlines")
    printer.warn("two lines")
    printer.warn("other", "where")
    assert out.getvalue().splitlines() == ["volren: warning: two lines", "volren: warning: other (where)"]


def _overflow() -> None:
    np.float64(1e308) * np.float64(10)  # RuntimeWarning: overflow encountered in scalar multiply


def test_library_warnings_are_one_line_once_with_their_origin():
    out = io.StringIO()
    with warnings.catch_warnings(), one_line_messages(LinePrinter(out)):
        warnings.simplefilter("always")
        for _ in range(3):
            _overflow()
        np.float64(1e308) * np.float64(10)  # the same message from another line
        warnings.warn("a library's\nmulti-line\n  warning", UserWarning, stacklevel=1)
        warnings.warn("ours, naming\nthe file", VolrenWarning, stacklevel=1)
    lines = out.getvalue().splitlines()
    assert len(lines) == 3, lines
    assert lines[0].startswith("volren: warning: overflow encountered in scalar multiply (RuntimeWarning at ")
    assert lines[1].startswith(
        "volren: warning: a library's multi-line warning (UserWarning at cli/test_messages.py:"
    )
    assert lines[2] == "volren: warning: ours, naming the file"


def test_log_records_are_one_line_once():
    out = io.StringIO()
    with one_line_messages(LinePrinter(out)):
        for _ in range(2):
            logging.getLogger("pyvista.test").warning("first line\nsecond line")
        logging.getLogger("numba.test").info("below WARNING: not shown")
    assert out.getvalue().splitlines() == ["volren: warning: pyvista.test: first line second line"]
    assert not any(
        isinstance(h, logging.Handler) and type(h).__name__ == "_LoggingHandler"
        for h in logging.getLogger().handlers
    )


@pytest.mark.parametrize("with_pyvista", [False, True])
def test_vtk_output_outside_a_catching_block_is_one_line(tmp_path, capfd, with_pyvista):
    from vtkmodules.vtkIOXML import vtkXMLImageDataReader

    if with_pyvista:
        import pyvista  # noqa: F401  (it sends VTK's errors to logging)
    out = io.StringIO()
    with one_line_messages(LinePrinter(out)):
        reader = vtkXMLImageDataReader()
        reader.SetFileName(str(tmp_path / "missing.vti"))
        reader.Update()
    lines = out.getvalue().splitlines()
    # through VTK's output window, or (once pyvista is imported) pyvista's observer and logging
    sources = ("volren: warning: VTK: ", "volren: warning: pyvista: ")
    assert lines and all(line.startswith(sources) for line in lines), lines
    assert any("missing.vti" in line for line in lines), lines
    assert all(len(line) < 400 for line in lines), lines  # vtkInformation dumps cut
    assert capfd.readouterr().err == ""  # vtkLogger printed nothing of its own


@pytest.fixture(scope="module")
def huge_inputs(tmp_path_factory):
    """A float64 volume spanning nearly all of float64 and a TF over the same span: numpy
    overflows on the way (value spans, TF crossings), which must not reach stderr as is."""
    import pyvista as pv

    folder = tmp_path_factory.mktemp("huge")
    grid = pv.ImageData(dimensions=(6, 6, 6))
    grid.point_data["v"] = np.linspace(-1.0, 1.0, 6**3) * 1.7e308
    grid.save(folder / "huge.vti")
    tf = {
        "version": 1,
        "kind": "1d",
        "color": [[-1.7e308, 1, 0, 0], [1.7e308, 0, 1, 0]],
        "opacity": [[-1.7e308, 0], [1.7e308, 1]],
        "opacity_unit_distance": 1.0,
    }
    (folder / "huge.tf.json").write_text(json.dumps(tf))
    return folder


@pytest.mark.parametrize("with_tf", [False, True])
def test_subprocess_render_of_absurd_values_says_one_line_per_message(tmp_path, huge_inputs, with_tf):
    args = [
        sys.executable,
        "-m",
        "volren.cli.main",
        "render",
        str(huge_inputs / "huge.vti"),
        "-o",
        str(tmp_path / "x.png"),
        "--size",
        "8",
        "--renderer",
        "reference",
    ]
    if with_tf:
        args += ["--tf", str(huge_inputs / "huge.tf.json")]
    env = {k: v for k, v in os.environ.items() if k != "PYTHONWARNINGS"}
    result = subprocess.run(args, capture_output=True, text=True, timeout=300, env=env)
    lines = result.stderr.splitlines()
    assert result.returncode in (0, 1), result.stderr
    assert all(line.startswith("volren: ") for line in lines), result.stderr
    counts = Counter(lines)
    assert max(counts.values(), default=1) == 1, counts
    assert "Traceback" not in result.stderr
