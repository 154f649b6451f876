"""Transfer-function files: our JSON round trip, its errors, and ParaView preset import."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
from vtkmodules.vtkRenderingCore import vtkColorTransferFunction

from volren.errors import VolrenError
from volren.io import load_transfer_function, save_transfer_function
from volren.model.transfer_function import TransferFunction1D


def write(path: Path, content) -> Path:
    path.write_text(content if isinstance(content, str) else json.dumps(content))
    return path


def fails(path: Path, *fragments: str, **kwargs) -> None:
    with pytest.raises(VolrenError) as info:
        load_transfer_function(path, **kwargs)
    message = str(info.value)
    assert message.startswith(f"{path}:"), message
    for fragment in fragments:
        assert fragment in message, message


# ----------------------------------------------------------------------------------- our format


def test_round_trip_keeps_unknown_keys(tmp_path):
    tf = TransferFunction1D([[0, 0, 0, 1], [10, 1, 0.5, 0]], [[0, 0], [4, 0.2], [10, 0.9]], 0.25)
    tf.extra["painted_by"] = {"tool": "editor", "strokes": [1, 2]}
    save_transfer_function(tf, tmp_path / "tf.json")
    saved = json.loads((tmp_path / "tf.json").read_text())
    assert saved["version"] == 1 and saved["kind"] == "1d"
    back = load_transfer_function(tmp_path / "tf.json")
    assert back == tf
    assert back.extra == {"painted_by": {"tool": "editor", "strokes": [1, 2]}}
    save_transfer_function(back, tmp_path / "again.json")
    assert json.loads((tmp_path / "again.json").read_text()) == saved


def test_shared_scene_tfs_load(shared_scenes):
    for path in sorted(shared_scenes.glob("*.json")):
        tf = load_transfer_function(path)
        assert tf.opacity_unit_distance > 0


def test_newer_version_is_refused(tmp_path):
    path = write(
        tmp_path / "new.json", {"version": 2, "kind": "1d", "color": [[0, 1, 1, 1]], "opacity": [[0, 1]]}
    )
    fails(path, "transfer function format version 2 is newer than this volren reads (up to 1)")


@pytest.mark.parametrize("version", [0, -1])
def test_versions_below_one_do_not_exist(tmp_path, version):
    doc = {"version": version, "kind": "1d", "color": [[0, 1, 1, 1]], "opacity": [[0, 1]]}
    fails(write(tmp_path / "old.json", doc), f"transfer function format version {version} does not exist")


def test_an_opacity_unit_distance_of_true_is_not_a_number(tmp_path):
    doc = {
        "version": 1,
        "kind": "1d",
        "color": [[0, 1, 1, 1]],
        "opacity": [[0, 1]],
        "opacity_unit_distance": True,
    }
    fails(write(tmp_path / "unit.json", doc), "opacity_unit_distance must be a number, got True")


@pytest.mark.parametrize(
    "content, fragment",
    [
        (
            '{"version": 1, "color": [[0, 1, 1, 1]],\n "opacity": [[0, 1]]\n "x": 1}',
            "invalid JSON at line 3, column 2",
        ),
        ("", "empty file"),
        ("[1, 2, 3]", "a JSON list that is not a list of ParaView presets"),
        ('"just a string"', "a transfer function must be a JSON object, got str"),
        ({"version": 1, "opacity": [[0, 1]]}, "missing 'color' list"),
        ({"version": 1, "color": "red", "opacity": [[0, 1]]}, "colour points must be numbers"),
        (
            {"version": 1, "color": [[0, "1", "0.5", "0"]], "opacity": [[0, 1]]},
            "colour points must be numbers, got '1'",
        ),
        (
            {"version": 1, "color": [[0, 1, 1, 1]], "opacity": [[0, False], [1, True]]},
            "opacity points must be numbers, got False",
        ),
        (
            {"version": 1, "color": [[0, 1, 1], [1, 1, 1, 1]], "opacity": [[0, 1]]},
            "colour points must be a non-empty list of 4-tuples",
        ),
        (
            {"version": 1, "color": [[0, 1, 1]], "opacity": [[0, 1]]},
            "colour points must be a non-empty list of 4-tuples",
        ),
        ({"version": 1, "color": [[0, 1, 1, 2]], "opacity": [[0, 1]]}, "colour values must lie in [0, 1]"),
        ({"version": "1", "color": [[0, 1, 1, 1]], "opacity": [[0, 1]]}, "'version' must be an integer"),
        (
            {"version": 1, "kind": "3d", "color": [[0, 1, 1, 1]], "opacity": [[0, 1]]},
            "unknown transfer-function kind '3d'",
        ),
        (
            {"version": 1, "color": [[0, 1, 1, 1]], "opacity": [[0, 1]], "opacity_unit_distance": -1},
            "must be positive",
        ),
    ],
)
def test_malformed_files(tmp_path, content, fragment):
    fails(write(tmp_path / "bad.json", content), fragment)


def test_missing_and_binary_files(tmp_path):
    fails(tmp_path / "nope.json", "no such file")
    (tmp_path / "bin.json").write_bytes(b"\xff\xfe\x00garbage\x80")
    fails(tmp_path / "bin.json", "not a text (UTF-8) file")
    fails(tmp_path, "is a folder")


def test_save_errors(tmp_path):
    tf = TransferFunction1D.ramp(0, 1)
    with pytest.raises(VolrenError, match="cannot write"):
        save_transfer_function(tf, tmp_path / "missing-folder" / "tf.json")
    with pytest.raises(VolrenError, match="expected a TransferFunction1D"):
        save_transfer_function({"color": []}, tmp_path / "tf.json")


# ------------------------------------------------------------------------------ ParaView presets

RGB = [-1.0, 0.1, 0.2, 0.9, 0.0, 1.0, 1.0, 1.0, 0.5, 0.9, 0.1, 0.1, 2.0, 0.2, 0.8, 0.2]
# x, alpha, midpoint, sharpness: non-default midpoints and sharpness, as ParaView's editor writes them
POINTS = [
    -1.0,
    0.0,
    0.5,
    0.0,
    -0.2,
    0.8,
    0.2,
    0.9,
    0.6,
    0.1,
    0.7,
    0.3,
    1.2,
    0.4,
    0.35,
    0.0,
    2.0,
    1.0,
    0.5,
    0.0,
]


def vtk_functions(rgb, points, space: str):
    ctf = vtkColorTransferFunction()
    getattr(ctf, f"SetColorSpaceTo{space}")()
    ctf.SetHSVWrap(False)
    for i in range(0, len(rgb), 4):
        ctf.AddRGBPoint(*rgb[i : i + 4])
    pwf = vtkPiecewiseFunction()
    for i in range(0, len(points), 4):
        pwf.AddPoint(*points[i : i + 4])
    return ctf, pwf


def assert_matches_vtk(tf: TransferFunction1D, ctf, pwf, lo: float, hi: float) -> None:
    xs = np.linspace(lo, hi, 5001)
    rgb, alpha = tf.sample(xs)
    np.testing.assert_allclose(rgb, [ctf.GetColor(x) for x in xs], atol=1e-3, rtol=0)
    np.testing.assert_allclose(alpha, [pwf.GetValue(x) for x in xs], atol=1e-3, rtol=0)


@pytest.mark.parametrize("space", ["RGB", "HSV", "Lab", "Diverging"])
def test_preset_matches_vtk(tmp_path, space):
    # ParaView's own writer leaves trailing commas; the loader must accept them
    text = json.dumps([{"Name": "test", "ColorSpace": space, "RGBPoints": RGB, "Points": POINTS}], indent=1)
    text = text.replace("]\n }", "],\n },").replace("}\n]", "},\n]")
    assert ",\n]" in text
    tf = load_transfer_function(write(tmp_path / "preset.json", text))
    assert_matches_vtk(tf, *vtk_functions(RGB, POINTS, space), -1.5, 2.5)
    assert tf.extra == {"name": "test"}


def test_cool_to_warm_diverging_preset(tmp_path):
    cool_to_warm = {
        "Name": "Cool to Warm",
        "ColorSpace": "Diverging",
        "NanColor": [1, 1, 0],
        "RGBPoints": [
            0,
            0.231373,
            0.298039,
            0.752941,
            0.5,
            0.865003,
            0.865003,
            0.865003,
            1,
            0.705882,
            0.0156863,
            0.14902,
        ],
        "Points": [0, 0, 0.5, 0, 1, 1, 0.5, 0],
    }
    tf = load_transfer_function(write(tmp_path / "ctw.json", cool_to_warm))
    assert_matches_vtk(
        tf, *vtk_functions(cool_to_warm["RGBPoints"], cool_to_warm["Points"], "Diverging"), -0.2, 1.2
    )
    assert len(tf.opacity_points) == 2  # linear opacity stays two nodes
    assert 2 < len(tf.color_points) < 400  # curved colours are sampled, not every table entry kept


def test_linear_parts_stay_exact(tmp_path):
    preset = {"Name": "lin", "ColorSpace": "RGB", "RGBPoints": [0, 0, 0, 0, 1, 1, 0, 0, 3, 1, 1, 1],
              "Points": [0, 0, 0.5, 0, 1, 0.5, 0.5, 0, 3, 1, 0.5, 0]}  # fmt: skip
    tf = load_transfer_function(write(tmp_path / "lin.json", preset))
    np.testing.assert_array_equal(tf.color_points, [[0, 0, 0, 0], [1, 1, 0, 0], [3, 1, 1, 1]])
    np.testing.assert_array_equal(tf.opacity_points, [[0, 0], [1, 0.5], [3, 1]])


def test_preset_without_opacity_gets_a_ramp(tmp_path):
    path = write(tmp_path / "p.json", {"Name": "gray", "RGBPoints": [2, 0, 0, 0, 6, 1, 1, 1]})
    tf = load_transfer_function(path)
    np.testing.assert_array_equal(tf.opacity_points, [[2, 0], [6, 1]])


def test_preset_by_name(tmp_path):
    presets = [{"Name": n, "RGBPoints": [0, v, v, v, 1, 1, 1, 1]} for n, v in (("a", 0.0), ("b", 0.5))]
    path = write(tmp_path / "many.json", presets)
    assert load_transfer_function(path).color_points[0, 1] == 0.0  # the first by default
    assert load_transfer_function(path, name="b").color_points[0, 1] == 0.5
    fails(path, "no preset named 'c'; available: 'a', 'b'", name="c")
    fails(
        write(tmp_path / "ours.json", TransferFunction1D.ramp(0, 1).to_dict()),
        "name= does not apply",
        name="a",
    )


@pytest.mark.parametrize(
    "preset, fragment",
    [
        ({"Name": "x", "IndexedColors": [1, 0, 0]}, "preset 'x' is an indexed (categorical) colour map"),
        ({"Name": "x", "ColorSpace": "RGB"}, "preset 'x' has no 'RGBPoints'"),
        ({"Name": "x", "RGBPoints": [0, 1, 1]}, "'RGBPoints' must hold groups of 4 numbers, got 3 numbers"),
        ({"Name": "x", "RGBPoints": [0, 1, 1, "a"]}, "'RGBPoints' must be a list of numbers"),
        (
            {"Name": "x", "RGBPoints": [1, 0, 0, 0, 0, 1, 1, 1]},
            "the x values of 'RGBPoints' must not decrease",
        ),
        ({"Name": "x", "RGBPoints": [0, 0, 0, 2]}, "must lie in [0, 1]"),
        ({"Name": "x", "RGBPoints": [0, 0, 0, 0], "ColorSpace": "CMYK"}, "unknown ColorSpace 'CMYK'"),
        (
            {"Name": "x", "RGBPoints": [0, 0, 0, 0, 1, 1, 1, 1], "Points": [0, 0, 0.5]},
            "'Points' must hold groups of 4",
        ),
        (
            {"Name": "x", "RGBPoints": [0, 0, 0, 0, 1, 1, 1, 1], "UseLogScale": True},
            "UseLogScale needs positive",
        ),
    ],
)
def test_malformed_presets(tmp_path, preset, fragment):
    fails(write(tmp_path / "bad.json", [preset]), fragment)


def smooth_preset(n: int, space: str = "RGB") -> dict:
    """n nodes of smoothly varying colour and opacity (opacity with ParaView's midpoints and sharpness)."""
    x = np.linspace(1.0, 1000.0, n)
    t = (x - 1.0) / 999.0
    rgb = np.column_stack([x, 0.5 + 0.5 * np.sin(6 * t), t, 1 - t])
    points = np.column_stack([x, t**2, np.full(n, 0.3), np.full(n, 0.2)])
    return {
        "Name": "big",
        "ColorSpace": space,
        "RGBPoints": rgb.ravel().tolist(),
        "Points": points.ravel().tolist(),
    }


def test_a_large_preset_matches_vtk_through_all_its_nodes(tmp_path):
    preset = smooth_preset(1500, "Lab")
    preset["RGBPoints"][4 * 7 : 4 * 8] = [
        preset["RGBPoints"][4 * 6],
        0.0,
        1.0,
        0.0,
    ]  # two nodes at one x: VTK keeps the last
    tf = load_transfer_function(write(tmp_path / "big.json", preset))
    assert_matches_vtk(tf, *vtk_functions(preset["RGBPoints"], preset["Points"], "Lab"), 0.0, 1001.0)


def test_a_large_preset_is_evaluated_by_small_vtk_functions(tmp_path, monkeypatch):
    """VTK sorts all nodes of a function on each insertion and scans them on each evaluation: one
    function through all of a preset's nodes made loading quadratic (20,000 nodes took minutes)."""
    from volren.io import _pv

    sizes = []

    def counting(build):
        def wrapped(nodes, *args):
            sizes.append(len(nodes))
            return build(nodes, *args)

        return wrapped

    monkeypatch.setattr(_pv, "color_table", counting(_pv.color_table))
    monkeypatch.setattr(_pv, "opacity_table", counting(_pv.opacity_table))
    load_transfer_function(write(tmp_path / "big.json", smooth_preset(1000)))
    assert sizes and max(sizes) <= 70


def test_a_preset_that_needs_too_many_points_is_refused_naming_the_file(tmp_path, monkeypatch):
    from volren.io import paraview_presets

    monkeypatch.setattr(paraview_presets, "MAX_POINTS", 300, raising=False)
    rng = np.random.default_rng(1)
    x = np.sort(rng.uniform(0, 1, 40))
    wild = {
        "Name": "wild",
        "ColorSpace": "Lab",
        "RGBPoints": np.column_stack([x, rng.uniform(0, 1, (40, 3))]).ravel().tolist(),
    }
    fails(write(tmp_path / "wild.json", wild), "preset 'wild': its colour map needs more than 300 points")
    fails(
        write(tmp_path / "long.json", smooth_preset(301)),
        "preset 'big': 'RGBPoints' has 301 points; a transfer function has at most 300",
    )


def test_a_lab_ciede2000_preset_of_many_points_is_refused(tmp_path):
    """VTK takes about 0.1 s per CIEDE2000 segment on every evaluation."""
    fails(
        write(tmp_path / "c.json", smooth_preset(65, "Lab/CIEDE2000")),
        "65 RGBPoints in the Lab/CIEDE2000 colour space",
    )


def test_nodes_on_straight_lines_are_dropped():
    from volren.io.paraview_presets import _drop_collinear, simplify_polyline

    x = np.linspace(0.0, 1.0, 5001)
    assert _drop_collinear(x, np.column_stack([x, 1 - x])).tolist() == [0, 5000]
    bent = np.column_stack([np.exp(2 * x), x])
    bent[1::2] = 0.5 * (bent[:-1:2] + bent[2::2])  # every other node on the chord of its neighbours
    kept = _drop_collinear(x, bent)
    assert kept.tolist() == list(range(0, 5001, 2))
    np.testing.assert_array_equal(kept, simplify_polyline(x, bent, 1e-12))
