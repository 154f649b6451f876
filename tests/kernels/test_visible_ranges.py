"""`visible_ranges` agrees with the largest opacity over each range (`max_opacity_between`)."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from volren.kernels.visible_ranges import visible_ranges
from volren.model.bricks import max_opacity_between
from volren.model.transfer_function import TransferFunction1D

values = st.floats(-2.0, 3.0, allow_nan=False).map(lambda v: round(v * 8) / 8)  # shared grid: ties and steps


@settings(max_examples=80, deadline=None)
@given(xs=st.lists(values, min_size=1, max_size=7), alphas=st.lists(st.sampled_from([0.0, 0.0, 0.3, 1.0]), min_size=7,
       max_size=7), ranges=st.lists(st.tuples(values, values), min_size=1, max_size=40))  # fmt: skip
def test_visible_exactly_where_the_largest_opacity_is_positive(xs, alphas, ranges) -> None:
    xs = sorted(xs)
    tf = TransferFunction1D([[0.0, 1.0, 1.0, 1.0]], [[x, a] for x, a in zip(xs, alphas, strict=False)])
    lo = np.array([min(r) for r in ranges])
    hi = np.array([max(r) for r in ranges])
    np.testing.assert_array_equal(visible_ranges(tf, lo, hi), max_opacity_between(tf, lo, hi) > 0)


def test_non_finite_ranges_are_not_visible_and_shapes_are_kept() -> None:
    tf = TransferFunction1D.constant(0.5)
    lo = np.array([[0.0, np.nan], [-np.inf, 1.0]])
    hi = np.array([[1.0, 2.0], [0.0, np.inf]])
    np.testing.assert_array_equal(visible_ranges(tf, lo, hi), [[True, False], [False, False]])
