"""`python -m benchmarks.tf_edit_latency`: a row per renderer and scene with three timings."""

from __future__ import annotations

import pytest

from benchmarks import tf_edit_latency


def test_a_row_with_three_timings(shared_data, capsys):
    argv = ["--shared", str(shared_data.parent), "--renderers", "shearwarp", "--datasets", "ironProt",
            "--size", "32", "--edits", "1"]  # fmt: skip
    assert tf_edit_latency.main(argv) == 0
    rows = [line for line in capsys.readouterr().out.splitlines() if line.startswith("| shearwarp |")]
    assert len(rows) == 1, rows
    cells = [c.strip() for c in rows[0].strip("|").split("|")]
    assert cells[1] == "ironProt smooth" and all(float(c) > 0 for c in cells[2:5]), cells


def test_the_edits_change_what_they_say():
    from volren.model.transfer_function import TransferFunction1D

    tf = TransferFunction1D([[0, 0.5, 0.5, 0.5], [10, 1, 1, 1]], [[2, 0.0], [8, 1.0]])
    opacity, version = tf.opacity_points.copy(), tf.version
    tf_edit_latency._nudge_colour(tf, 0)
    assert tf.version > version and (tf.opacity_points == opacity).all()
    tf_edit_latency._move_opacity(tf, 0, span=10.0)
    assert tf.opacity_points[:, 0].tolist() == pytest.approx([2.1, 8.1])
    tf_edit_latency._move_opacity(tf, 1, span=10.0)
    assert tf.opacity_points[:, 0].tolist() == pytest.approx([2.0, 8.0])
