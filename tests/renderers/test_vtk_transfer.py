"""Our TF in VTK's terms: uniform mappers get it as is, unstructured ones in extinction form."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from volren.model.transfer_function import MAX_OPACITY, TransferFunction1D
from volren.renderers.vtk_mappers.transfer import (
    MASK_COLUMNS,
    MASK_ROWS,
    MAX_EXTINCTION_ERROR,
    extinction_nodes,
    masked_function,
    masked_table,
    replace_nonfinite,
    uniform_functions,
    unstructured_functions,
)

pytestmark = pytest.mark.vtk


def evaluate(color, opacity, xs):
    rgb = np.array([color.GetColor(x) for x in xs])
    alpha = np.array([opacity.GetValue(x) for x in xs])
    return rgb, alpha


def extinction(alpha):
    return -np.log1p(-np.minimum(alpha, MAX_OPACITY))


TF = TransferFunction1D(
    [[0, 0, 0, 1], [40, 1, 0, 0], [100, 0, 1, 0]], [[10, 0], [20, 1.0], [60, 0.3], [80, 0.0]], 2.0
)


def test_uniform_functions_reproduce_the_tf():
    xs = np.linspace(-20, 120, 701)
    rgb, alpha = evaluate(*uniform_functions(TF, data_lo=0.0), xs)
    expected_rgb, expected_alpha = TF.sample(xs)
    np.testing.assert_allclose(rgb, expected_rgb, atol=1e-9)
    np.testing.assert_allclose(alpha, expected_alpha, atol=1e-9)


def test_unstructured_functions_give_extinction_and_a_colour_at_every_opacity_node():
    color, opacity = unstructured_functions(TF, data_lo=0.0)
    nodes, _ = extinction_nodes(TF)
    assert color.GetSize() == opacity.GetSize() == len(nodes)
    xs = np.linspace(-20, 120, 2001)
    rgb, y = evaluate(color, opacity, xs)
    expected_rgb, expected_alpha = TF.sample(xs)
    np.testing.assert_allclose(rgb, expected_rgb, atol=1e-9)
    assert np.abs(y - extinction(expected_alpha)).max() <= MAX_EXTINCTION_ERROR * 1.0001


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(0, 100), st.floats(0, 1)), min_size=1, max_size=6))
@example([(0.0, 1.0), (1.0, 0.99999)])  # a ramp that starts inside the opacity clamp
def test_extinction_nodes_keep_linear_interpolation_close(points):
    tf = TransferFunction1D([[0, 1, 1, 1]], [list(p) for p in points])
    nodes, values = extinction_nodes(tf)
    assert np.all(np.diff(nodes) >= 0)
    # Where the TF steps (repeated x), the nodes step too: compare away from the steps.
    xs = np.linspace(-1, 101, 4001)
    xs = xs[np.min(np.abs(xs[:, None] - tf.breakpoints()[None, :]), axis=1) > 1e-6]
    y = extinction(tf.sample(xs)[1])
    y_nodes = extinction(values[:, 3])
    # np.interp with repeated nodes takes the right-hand value at a repeated x, like the TF.
    assert np.abs(np.interp(xs, nodes, y_nodes) - y).max() <= MAX_EXTINCTION_ERROR * 1.0001
    assert len(nodes) <= len(tf.breakpoints()) * 257


def test_steps_stay_steps():
    tf = TransferFunction1D(
        [[0, 0, 0, 0], [5, 1, 1, 1], [5, 0, 0, 0], [9, 0, 0, 0]], [[0, 0.2], [5, 0.2], [5, 0.8]]
    )
    for build in (uniform_functions, unstructured_functions):
        color, opacity = build(tf, 0.0)
        convert = (lambda a: a) if build is uniform_functions else extinction
        assert opacity.GetValue(4.999) == pytest.approx(convert(0.2), abs=1e-3)
        assert opacity.GetValue(5.001) == pytest.approx(convert(0.8), abs=1e-6)
        assert color.GetColor(4.999)[0] == pytest.approx(1.0, abs=1e-3)
        assert color.GetColor(5.001)[0] == pytest.approx(0.0, abs=1e-3)


def test_nonfinite_values_become_a_transparent_sentinel():
    values = np.array([1.0, np.nan, 3.0, np.inf], np.float32)
    replaced, sentinel = replace_nonfinite(values, (1.0, 3.0))
    assert sentinel == -1.0 and replaced.tolist() == [1.0, -1.0, 3.0, -1.0]
    assert replace_nonfinite(np.arange(3, dtype=np.uint8), (0, 2))[1] is None
    for build, expected in ((uniform_functions, 0.5), (unstructured_functions, extinction(0.5))):
        _, opacity = build(TransferFunction1D.constant(0.5), 1.0, sentinel)
        assert opacity.GetValue(sentinel) == 0.0 and opacity.GetValue(0.9) == 0.0
        assert opacity.GetValue(1.0) == pytest.approx(expected)
        assert opacity.GetValue(2.0) == pytest.approx(expected)


def test_the_masked_table_is_the_tf_per_sample_where_all_corners_are_finite():
    """Top row (finite interpolates to 1): the TF at the texel centres of the scalar range, its
    opacity that of one sample step; every other row transparent."""
    table = masked_table(TF, (-20.0, 120.0), sample_distance=0.5)
    assert table.shape == (MASK_ROWS, MASK_COLUMNS, 4) and table.dtype == np.float32
    assert not table[:-1].any()
    xs = -20.0 + (np.arange(MASK_COLUMNS) + 0.5) / MASK_COLUMNS * 140.0
    rgb, alpha = TF.sample(xs)
    np.testing.assert_allclose(table[-1, :, :3], rgb, atol=1e-6)
    np.testing.assert_allclose(
        table[-1, :, 3], 1.0 - (1.0 - np.minimum(alpha, MAX_OPACITY)) ** 0.25, atol=1e-6
    )
    image = masked_function(TF, (-20.0, 120.0), 0.5)
    assert image.GetDimensions() == (MASK_COLUMNS, MASK_ROWS, 1)
    assert image.GetPointData().GetScalars().GetNumberOfComponents() == 4


def test_large_tfs_reach_vtk_node_for_node():
    """The nodes go to VTK as whole arrays (VTK re-sorts after every single AddPoint, which made
    20,000 points take seconds): every node arrives, in order, steps kept."""
    n = 50_000
    xs = np.linspace(0.0, 1.0, n)
    xs[100] = xs[101]  # a step
    alphas = (np.arange(n) % 2) * 0.5
    tf = TransferFunction1D(
        color=np.stack([xs, alphas, 1 - alphas, alphas], axis=1), opacity=np.stack([xs, alphas], axis=1)
    )
    color, opacity = uniform_functions(tf, 0.0)
    assert color.GetSize() == n and opacity.GetSize() == n
    node = [0.0] * 6
    for i in (0, 100, 101, 4321, n - 1):
        color.GetNodeValue(i, node)
        assert node[:4] == [xs[i], alphas[i], 1 - alphas[i], alphas[i]]
        value = [0.0] * 4
        opacity.GetNodeValue(i, value)
        assert value[:2] == [xs[i], alphas[i]]
