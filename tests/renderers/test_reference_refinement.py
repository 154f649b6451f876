"""The reference's refinement, shared by 1D and 2D TFs: the cut table of each kind and the rule that
stops the levels."""

from __future__ import annotations

import numpy as np
import pytest

from volren.kernels.tf_eval import pack_tf
from volren.model import TFWidget, TransferFunction1D, TransferFunction2D
from volren.renderers.reference.refinement import ASYMPTOTIC_RATIO, compute_cuts, converged
from volren.renderers.reference.tf2d import pack_tf2d

# two intervals on which s runs linearly: s = u on [0, 4] and s = 4 - u on [0, 2] (grad s = (1, 0, 0))
TA = np.array([0.0, 10.0])
TB = np.array([4.0, 12.0])
P = np.array([[0.0, 1.0, 0.0, 0.0], [4.0, -1.0, 0.0, 0.0]])
G = np.zeros((2, 3, 4))
G[:, 0, 0] = 1.0


def test_a_1d_tf_is_cut_at_its_breakpoints_in_ray_order():
    tf = TransferFunction1D([[0.0, 1.0, 1.0, 1.0]], [[1.0, 0.0], [2.5, 0.5], [3.5, 0.2]])
    offsets, cuts = compute_cuts(TA, TB, P, G, 2, pack_tf(tf), None, False, 0.0)
    np.testing.assert_array_equal(offsets, [0, 4, 7])
    np.testing.assert_array_equal(
        cuts, [1.0, 2.5, 3.5, 4.0, 0.5, 1.5, 2.0]
    )  # the second runs down from s = 4


def test_a_2d_tf_is_cut_at_its_widgets_value_edges_in_ray_order():
    """|grad s| = 1 lies inside the box's gradient band, so only its value edges cut."""
    tf = TransferFunction2D(
        (0.0, 4.0), (0.0, 3.0), [TFWidget.box((1.0, 3.0), (0.5, 2.0), (0.1, 0.8, 0.3), 0.4)]
    )
    offsets, cuts = compute_cuts(TA, TB, P, G, 2, None, pack_tf2d(tf), False, 0.0)
    np.testing.assert_array_equal(offsets, [0, 3, 5])
    np.testing.assert_array_equal(cuts, [1.0, 3.0, 4.0, 1.0, 2.0])


@pytest.mark.parametrize(
    "level, change, last, stops",
    [
        (1, 0.99 / ASYMPTOTIC_RATIO, np.inf, True),  # level 1: below tol / ratio
        (1, 1.0 / ASYMPTOTIC_RATIO, np.inf, False),
        (2, 0.99, 0.99 * ASYMPTOTIC_RATIO, True),  # later: below tol after a change below ratio * tol
        (2, 0.99, ASYMPTOTIC_RATIO, False),
        (3, 1.0, 0.5, False),
    ],
)
def test_levels_stop_by_one_rule(level, change, last, stops):
    assert converged(level, change, last, 1.0) is stops
