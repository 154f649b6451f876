"""Limits with a one-line error instead of unbounded cost: TF points, 2D widgets, JSON nesting and
size, and the type of a scene's renderer options."""

from __future__ import annotations

import json

import numpy as np
import pytest

from volren.errors import VolrenError
from volren.io import load_scene, load_transfer_function
from volren.io.json_text import MAX_BYTES, MAX_DEPTH, nesting_depth, read_json
from volren.model.settings import RenderSettings
from volren.model.transfer_function import MAX_POINTS, TransferFunction1D
from volren.model.transfer_function_2d import MAX_WIDGETS, TFWidget, TransferFunction2D


def ramp_points(n: int) -> list[list[float]]:
    return [[float(x), 0.5] for x in np.linspace(0.0, 1.0, n)]


def test_tf_points_up_to_the_limit_and_not_beyond():
    assert (
        len(TransferFunction1D(color=[[0, 1, 1, 1]], opacity=ramp_points(MAX_POINTS)).opacity_points)
        == MAX_POINTS
    )
    with pytest.raises(
        VolrenError, match=f"{MAX_POINTS + 1} points; a transfer function has at most {MAX_POINTS}"
    ):
        TransferFunction1D(color=[[0, 1, 1, 1]], opacity=ramp_points(MAX_POINTS + 1))


def widget(i: int) -> TFWidget:
    """Box widgets that differ (no two alike)."""
    return TFWidget(
        "box", (1, 0, 0), 0.5, value_range=(i / (2 * MAX_WIDGETS), 1.0), gradient_range=(0.0, 1.0)
    )


def test_2d_widgets_up_to_the_limit_and_not_beyond():
    tf = TransferFunction2D((0, 1), (0, 2), [widget(i) for i in range(MAX_WIDGETS)])
    with pytest.raises(VolrenError, match=f"at most {MAX_WIDGETS} widgets"):
        tf.add_widget(widget(0))
    assert len(tf.widgets) == MAX_WIDGETS
    with pytest.raises(VolrenError, match=f"at most {MAX_WIDGETS} widgets"):
        TransferFunction2D((0, 1), (0, 2), [widget(i) for i in range(MAX_WIDGETS + 1)])
    data = tf.to_dict()
    data["widgets"] = data["widgets"] * 2
    with pytest.raises(VolrenError, match=f"{2 * MAX_WIDGETS} widgets; at most {MAX_WIDGETS}"):
        TransferFunction2D.from_dict(data)


def test_nesting_depth_skips_strings():
    assert nesting_depth('{"a": [1, "[[[{", {"b": "\\"]"}]}') == 3
    assert nesting_depth("[]") == 1 and nesting_depth("1") == 0


def test_deeply_nested_json_is_one_line_naming_the_file(tmp_path):
    path = tmp_path / "deep.json"
    path.write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(
        VolrenError,
        match=rf"deep\.json: arrays and objects nest 100000 deep; volren reads at most {MAX_DEPTH}",
    ):
        load_transfer_function(path)
    path.write_text("[" * MAX_DEPTH + "]" * MAX_DEPTH)
    assert nesting_depth(path.read_text()) == MAX_DEPTH
    read_json(path)  # at the limit: read


def test_oversized_json_is_refused_before_reading(tmp_path):
    path = tmp_path / "big.json"
    with open(path, "wb") as f:
        f.truncate(MAX_BYTES + 1)  # sparse: no time or disk spent
    with pytest.raises(VolrenError, match=r"big\.json: .* too large for a volren JSON file"):
        read_json(path)


@pytest.mark.parametrize("options", [[1, 2], "fast", 3, {1: "x"}])
def test_options_of_the_wrong_type_are_one_line(tmp_path, options):
    with pytest.raises(VolrenError, match="render setting options must map names to values"):
        RenderSettings(options=options)
    scene = tmp_path / "s.json"
    scene.write_text(
        json.dumps(
            {
                "version": 1,
                "transfer_function": {"color": [[0, 1, 1, 1]], "opacity": [[0, 1]]},
                "settings": {"options": options if not isinstance(options, dict) else {"1": 2}},
            }
        )
    )
    if isinstance(options, dict):
        return  # JSON keys are strings: {1: "x"} cannot come from a file
    with pytest.raises(VolrenError, match=r"s\.json: render setting options must map names to values"):
        load_scene(scene, load_volume=False)
