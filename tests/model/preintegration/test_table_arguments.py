"""Arguments of the pre-integration functions and of LengthAxis: every bad one is a VolrenError
naming the problem, raised before anything is computed or allocated; and an explicit value range
wider than the TF's control points works, with the TF constant beyond its end points."""

from __future__ import annotations

import math
import tracemalloc

import numpy as np
import pytest

from tests.model.preintegration.tfs import smooth
from volren.errors import VolrenError
from volren.model.preintegration import (
    LengthAxis,
    lighting_tables,
    preintegrate,
    preintegrate_approximate,
    preintegrate_brute_force,
)
from volren.model.preintegration import tables as tables_module
from volren.model.preintegration.tables import MAX_BINS, MAX_TABLE_BYTES
from volren.model.transfer_function import TransferFunction1D

ALL = (preintegrate, lighting_tables, preintegrate_brute_force, preintegrate_approximate)
#: The functions that take `lengths=` (3D tables); preintegrate_approximate is 2D only.
WITH_LENGTHS = (preintegrate, lighting_tables, preintegrate_brute_force)
NAN, INF = math.nan, math.inf

#: (overrides of tf=smooth(), n=8, step=0.5; a fragment the message must contain; functions)
CASES = [
    # the table size n
    (dict(n=1), "n >= 2", ALL),
    (dict(n=0), "n >= 2", ALL),
    (dict(n=-3), "n >= 2", ALL),
    (dict(n=2.5), "integer size n", ALL),
    (dict(n=8.0), "integer size n", ALL),
    (dict(n=True), "integer size n", ALL),
    (dict(n="8"), "integer size n", ALL),
    # the segment length
    (dict(step=0), "step must be positive", ALL),
    (dict(step=-0.5), "step must be positive", ALL),
    (dict(step=NAN), "step must be positive and finite", ALL),
    (dict(step=INF), "step must be positive and finite", ALL),
    (dict(step=[0.5]), "step must be one number", ALL),
    (dict(step=np.array([0.5, 1.0])), "step must be one number", ALL),
    (dict(step="abc"), "step", ALL),
    (dict(step=None), "exactly one of step", ALL),
    (dict(lengths=[0.5]), "exactly one of step", WITH_LENGTHS),
    # the lengths of a 3D table
    (dict(step=None, lengths=[]), "non-empty", WITH_LENGTHS),
    (dict(step=None, lengths=[[0.5, 1.0]]), "1D", WITH_LENGTHS),
    (dict(step=None, lengths=0.5), "1D", WITH_LENGTHS),
    (dict(step=None, lengths=[0.5, -1.0]), ">= 0", WITH_LENGTHS),
    (dict(step=None, lengths=[0.5, NAN]), "finite", WITH_LENGTHS),
    (dict(step=None, lengths=[INF]), "finite", WITH_LENGTHS),
    (dict(step=None, lengths=["a"]), "lengths must be numbers", WITH_LENGTHS),
    # the value range
    (dict(value_range=(1.0, 0.0)), "lo <= hi", ALL),
    (dict(value_range=(0.0, INF)), "finite", ALL),
    (dict(value_range=(-INF, 0.0)), "finite", ALL),
    (dict(value_range=(NAN, 1.0)), "finite", ALL),
    (dict(value_range=(-1e308, 1e308)), "finite", ALL),  # hi - lo overflows
    (dict(value_range=(0.0,)), "value range", ALL),
    (dict(value_range=(0.0, "a")), "value range", ALL),
    # oversampling and the number of bins
    (dict(oversampling=0), "oversampling must be an integer >= 1", ALL),
    (dict(oversampling=-2), "oversampling must be an integer >= 1", ALL),
    (dict(oversampling=1.5), "oversampling must be an integer >= 1", ALL),
    (dict(oversampling=True), "oversampling must be an integer >= 1", ALL),
    (dict(oversampling=MAX_BINS // 7 + 1), f"exceeds {MAX_BINS} bins", ALL),
    (dict(n=MAX_BINS + 2, oversampling=1), f"exceeds {MAX_BINS} bins", ALL),
    (dict(n=MAX_BINS + 2), f"exceeds {MAX_BINS} bins", ALL),  # the automatic oversampling is 1
    # the size of the output
    (dict(n=20000, oversampling=1), "GiB", ALL),
    (dict(n=4096, oversampling=1, step=None, lengths=np.linspace(0.1, 1.0, 64)), "GiB", WITH_LENGTHS),
    # the transfer function
    (dict(tf=None), "1D transfer function, got NoneType", ALL),
    (dict(tf={"color": [[0, 1, 1, 1]], "opacity": [[0, 1]]}), "1D transfer function, got dict", ALL),
    (dict(tf=np.zeros((8, 4), dtype=np.float32)), "1D transfer function, got ndarray", ALL),
]


def _cases():
    for overrides, fragment, functions in CASES:
        for function in functions:
            label = ",".join(f"{k}={_short(v)}" for k, v in overrides.items())
            yield pytest.param(function, overrides, fragment, id=f"{function.__name__}-{label}")


def _short(value: object) -> str:
    text = type(value).__name__ if isinstance(value, (np.ndarray, dict)) else repr(value)
    return text if len(text) <= 20 else text[:17] + "..."


@pytest.fixture
def nothing_computed(monkeypatch):
    """Makes any computation fail loudly: validation must come before all work and allocation."""

    def refuse(*args, **kwargs):
        raise AssertionError("a table was computed for bad arguments")

    for name in ("_exact_tables", "tf_bins", "point_values", "integral_function_table"):
        monkeypatch.setattr(tables_module, name, refuse)


@pytest.mark.parametrize("function, overrides, fragment", list(_cases()))
def test_bad_argument_is_a_volren_error_naming_the_problem(function, overrides, fragment, nothing_computed):
    """Users and renderers get one clear message instead of a numpy error, a hang or a huge allocation."""
    kwargs = {"tf": smooth(), "n": 8, "step": 0.5, **overrides}
    tf = kwargs.pop("tf")
    with pytest.raises(VolrenError) as info:
        function(tf, **kwargs)
    assert fragment in str(info.value), str(info.value)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("function", [lighting_tables, preintegrate_brute_force])
def test_size_limit_counts_both_lighting_tables(function, nothing_computed):
    """Lighting output is two tables: a size whose one table fits but whose pair does not is refused."""
    n = 11586
    assert n * n * 16 <= MAX_TABLE_BYTES < 2 * n * n * 16
    kwargs = {"lighting": True} if function is preintegrate_brute_force else {}
    with pytest.raises(VolrenError, match="GiB"):
        function(smooth(), n, step=0.5, oversampling=1, **kwargs)


@pytest.mark.parametrize("function", ALL)
@pytest.mark.parametrize("n", [20000, 100000])
def test_huge_table_fails_fast_without_allocating(function, n):
    """A mistyped size must fail before touching memory (tracemalloc sees numpy's allocations)."""
    tf = smooth()
    tracemalloc.start()
    try:
        with pytest.raises(VolrenError):
            function(tf, n, step=0.5)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 1 << 20, f"{peak} bytes allocated before refusing n={n}"


@pytest.mark.parametrize(
    "kwargs, fragment",
    [
        (dict(max_length=0.0), "positive and finite"),
        (dict(max_length=-1.0), "positive and finite"),
        (dict(max_length=NAN), "positive and finite"),
        (dict(max_length=INF), "positive and finite"),
        (dict(max_length=1.0, count=0), "whole number >= 1"),
        (dict(max_length=1.0, count=-4), "whole number >= 1"),
        (dict(max_length=1.0, count=2.5), "whole number >= 1"),
        (dict(max_length=1.0, count=4.0), "whole number >= 1"),
        (dict(max_length=1.0, count=True), "whole number >= 1"),
    ],
)
def test_bad_length_axis_is_a_volren_error(kwargs, fragment):
    """A 3D table's length axis needs a positive finite longest length and a whole count >= 1."""
    with pytest.raises(VolrenError, match=fragment):
        LengthAxis(**kwargs)


def test_good_length_axis_accepts_numpy_integers():
    """The validation must not reject ordinary numpy integer counts."""
    axis = LengthAxis(max_length=2.0, count=np.int64(4))
    np.testing.assert_allclose(axis.lengths, [0.5, 1.0, 1.5, 2.0])


# ------------------------------------------------------------------- a wider value range
def _two_sided_tf() -> TransferFunction1D:
    """Non-zero, different opacity and colour at both ends of [0, 1] (so both extensions show)."""
    return TransferFunction1D(
        [[0, 1, 0, 0], [0.5, 0.2, 0.9, 0.1], [1, 0, 0, 1]],
        [[0, 0.3], [0.6, 0.05], [1, 0.8]],
        opacity_unit_distance=0.5,
    )


def _homogeneous(tf: TransferFunction1D, value: float, length: float) -> np.ndarray:
    """Closed form of a homogeneous segment: alpha = 1 - exp(-tau L), colour = c alpha."""
    rgb, _ = tf.sample(value)
    alpha = -math.expm1(-float(tf.extinction(value)) * length)
    return np.append(rgb * alpha, alpha)


# value_range (-1, 2) with n = 13: s_k = -1 + k / 4, so k <= 4 is at or below 0 and k >= 8 at or above 1.
BELOW = [(0, 0), (0, 3), (3, 0), (1, 4), (4, 4)]
ABOVE = [(8, 8), (8, 12), (12, 9), (10, 11), (12, 12)]


@pytest.mark.parametrize("function", [preintegrate, preintegrate_brute_force])
@pytest.mark.parametrize("step", [0.05, 0.8, 6.0])
def test_wider_value_range_uses_the_constant_extension(function, step):
    """Outside its control points the TF is constant, so every entry between two values beyond
    the same end is the homogeneous segment of that end's colour and opacity."""
    tf = _two_sided_tf()
    assert tf.value_range == (0.0, 1.0)
    table = function(tf, 13, step, value_range=(-1.0, 2.0), oversampling=2)
    assert table.shape == (13, 13, 4)
    for (i, j), end in [(ij, 0.0) for ij in BELOW] + [(ij, 1.0) for ij in ABOVE]:
        np.testing.assert_allclose(table[i, j], _homogeneous(tf, end, step), rtol=1e-6, atol=1e-7)
    # ... and entries crossing the control points differ from both ends (the range is really used)
    assert not np.allclose(table[2, 10], _homogeneous(tf, 0.0, step))
    assert not np.allclose(table[2, 10], _homogeneous(tf, 1.0, step))


def test_wider_value_range_in_lighting_tables_splits_the_homogeneous_segment():
    """Beyond the ends the lighting split is the homogeneous one: back-weighted emission
    c (1 - e^-x (1 + x)) / x with x = tau L, front = plain colour - back, opacity as plain."""
    tf = _two_sided_tf()
    step = 0.8
    light = lighting_tables(tf, 13, step, value_range=(-1.0, 2.0), oversampling=2, cache=None)
    for (i, j), end in [(ij, 0.0) for ij in BELOW] + [(ij, 1.0) for ij in ABOVE]:
        plain = _homogeneous(tf, end, step)
        rgb, _ = tf.sample(end)
        x = float(tf.extinction(end)) * step
        back = (1.0 - math.exp(-x) * (1.0 + x)) / x
        np.testing.assert_allclose(light.opacity[i, j], plain[3], rtol=1e-6)
        np.testing.assert_allclose(light.diffuse_back[i, j], rgb * back, rtol=1e-5, atol=1e-7)
        np.testing.assert_allclose(light.specular_back[i, j], back, rtol=1e-5, atol=1e-7)
        np.testing.assert_allclose(light.diffuse_front[i, j], plain[:3] - rgb * back, rtol=1e-5, atol=1e-7)


def test_wider_value_range_in_the_approximate_table_uses_the_constant_extension():
    """Engel's table beyond the TF's ends: exact opacity, unattenuated colour L tau c (clamped to 1)."""
    tf = _two_sided_tf()
    step = 0.8
    table = preintegrate_approximate(tf, 13, step, value_range=(-1.0, 2.0), oversampling=2)
    for (i, j), end in [(ij, 0.0) for ij in BELOW] + [(ij, 1.0) for ij in ABOVE]:
        rgb, _ = tf.sample(end)
        depth = float(tf.extinction(end)) * step
        expected = np.append(np.minimum(rgb * depth, 1.0), -math.expm1(-depth))
        np.testing.assert_allclose(table[i, j], expected, rtol=1e-6, atol=1e-7)
