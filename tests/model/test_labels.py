"""Label volumes and per-label transfer functions (`volren.model.labels`)."""

from __future__ import annotations

import numpy as np
import pytest

from volren.errors import VolrenError
from volren.model import TransferFunction1D, UniformVolume
from volren.model.labels import (
    MAX_LABEL,
    PALETTE,
    LabelMap,
    LabelStyle,
    LabelTransferFunction,
    cell_label_weights,
)

BASE = TransferFunction1D([[0.0, 0.2, 0.4, 0.6], [10.0, 1.0, 1.0, 1.0]], [[0.0, 0.0], [10.0, 0.8]])


def _labels(*present: int) -> LabelMap:
    values = np.zeros((2, 2, len(present)), np.int32)
    values[..., :] = present
    return LabelMap(values, names={present[-1]: "last"}, colors={present[-1]: (0.0, 0.5, 1.0)})


def test_labels_are_stored_small_and_listed() -> None:
    assert LabelMap(np.array([[[0, 3], [3, 7]]] * 2, np.int64)).values.dtype == np.uint8
    wide = LabelMap(np.full((2, 2, 2), 300, np.int32))
    assert wide.values.dtype == np.uint16 and wide.present == (300,) and wide.max_label == 300
    assert LabelMap(np.ones((2, 2, 2), np.float32)).present == (1,)  # whole numbers stored as floats


@pytest.mark.parametrize(
    ("values", "message"),
    [
        (np.full((2, 2, 2), -1), "0..65535"),
        (np.full((2, 2, 2), MAX_LABEL + 1), "0..65535"),
        (np.full((2, 2, 2), 1.5), "whole numbers"),
        (np.full((2, 2, 2), np.nan), "whole numbers"),
        (np.array(["a"] * 8).reshape(2, 2, 2), "integers"),
        (np.zeros((2, 2)), "3D"),
    ],
)
def test_bad_labels_are_refused_in_one_line(values: np.ndarray, message: str) -> None:
    with pytest.raises(VolrenError, match=message) as error:
        LabelMap(values, name="seg.nii.gz")
    assert "seg.nii.gz" in str(error.value) and "\n" not in str(error.value)


def test_labels_must_lie_on_the_volumes_grid() -> None:
    labels = LabelMap(np.zeros((3, 4, 5), np.uint8), name="seg.nrrd")
    assert UniformVolume(np.zeros((3, 4, 5)), labels=labels).labels is labels
    with pytest.raises(VolrenError, match=r"seg.nrrd: the label volume is 5x4x3 but ct is 5x4x4"):
        UniformVolume(np.zeros((4, 4, 5)), name="ct", labels=labels)


def test_the_default_look_colours_every_label_but_the_background() -> None:
    labels = _labels(0, 2, 9)
    tf = LabelTransferFunction.for_labels(BASE, labels)
    assert tf.effective_tf(0) is BASE
    assert tf.style(2).color == PALETTE[0]
    assert tf.style(9).color == (0.0, 0.5, 1.0)  # the file's colour
    rgb, alpha = tf.effective_tf(9).sample([5.0])
    np.testing.assert_allclose(rgb, [[0.0, 0.5, 1.0]])
    np.testing.assert_allclose(alpha, BASE.sample([5.0])[1])


def test_classes_group_labels_that_draw_alike() -> None:
    red = LabelStyle(color=(1.0, 0.0, 0.0))
    tf = LabelTransferFunction(
        BASE, {1: red, 2: red, 3: LabelStyle(visible=False), 4: LabelStyle(opacity=0.0)}
    )
    classes = tf.classes(6)
    assert classes.lookup.tolist() == [0, 1, 1, -1, -1, 0, 0]
    assert len(classes.tfs) == 2 and classes.tfs[0] is BASE
    assert tf.classes(2).lookup.tolist() == [0, 1, 1]


def test_an_own_tf_and_an_opacity_scale() -> None:
    own = TransferFunction1D.ramp(0.0, 1.0, 0.5, (0.0, 1.0, 0.0))
    tf = LabelTransferFunction(BASE, {1: LabelStyle(tf=own), 2: LabelStyle(tf=own, opacity=4.0)})
    assert tf.effective_tf(1) is own
    _, alpha = tf.effective_tf(2).sample([0.25, 1.0])
    np.testing.assert_allclose(alpha, [0.5, 1.0])  # 4 x 0.125, and 4 x 0.5 clipped to 1
    assert tf.value_range == (0.0, 10.0)


def test_the_json_form_round_trips_and_the_digest_follows_every_edit() -> None:
    own = TransferFunction1D.ramp(0.0, 1.0, 0.5)
    tf = LabelTransferFunction(
        BASE.copy(), {3: LabelStyle(color=(0.1, 0.2, 0.3), opacity=0.5), 7: LabelStyle(tf=own)}
    )
    tf.hide([0])
    again = LabelTransferFunction.from_dict(tf.to_dict())
    assert again.to_dict() == tf.to_dict() and again.digest() == tf.digest()
    before = tf.digest()
    tf.base.set_opacity_points([[0.0, 0.0], [10.0, 0.3]])  # an edit in place, as the app's editor makes
    assert tf.digest() != before
    with pytest.raises(VolrenError, match="unknown key"):
        LabelTransferFunction.from_dict({"version": 1, "kind": "labels", "base": BASE.to_dict(),
                                         "labels": {"2": {"colour": [1, 0, 0]}}})  # fmt: skip
    with pytest.raises(VolrenError, match="not a whole number"):
        LabelTransferFunction.from_dict(
            {"version": 1, "kind": "labels", "base": BASE.to_dict(), "labels": {"x": {}}}
        )
    with pytest.raises(VolrenError, match="newer"):
        LabelTransferFunction.from_dict({"version": 2, "kind": "labels", "base": BASE.to_dict()})


def test_the_weights_of_a_cells_labels_sum_to_one_and_interpolate_the_indicators() -> None:
    corners = np.array([0, 3, 0, 3, 0, 3, 5, 3])
    rng = np.random.default_rng(0)
    f = rng.uniform(size=(3, 50))
    weights = cell_label_weights(corners, *f)
    np.testing.assert_allclose(sum(weights.values()), 1.0)
    np.testing.assert_allclose(weights[3], f[0])  # label 3 holds every corner at x = 1
    np.testing.assert_allclose(weights[5], (1 - f[0]) * f[1] * f[2])


def test_the_models_extinction_is_the_weighted_sum_of_the_labels() -> None:
    tf = LabelTransferFunction(BASE, {1: LabelStyle(color=(1.0, 0.0, 0.0)), 2: LabelStyle(visible=False)})
    s = np.array([2.0, 6.0])
    tau, q = tf.extinction_emission(s, {0: [0.25, 0.5], 1: [0.5, 0.25], 2: [0.25, 0.25]})
    base_tau = BASE.extinction(s)
    np.testing.assert_allclose(tau, 0.75 * base_tau)  # the hidden label takes weight, adds nothing
    rgb, _ = BASE.sample(s)
    np.testing.assert_allclose(
        q, ([0.25, 0.5] * base_tau)[:, None] * rgb + ([0.5, 0.25] * base_tau)[:, None] * [1, 0, 0]
    )


def test_cell_classes_are_the_class_all_eight_corners_share() -> None:
    """Against the definition, cell by cell: labels of one class meeting (a uniform cell), a
    hidden label, and the last plane, row and column (no cell starts there)."""
    from volren.model.labels import MIXED, boundary_cells, cell_classes

    rng = np.random.default_rng(5)
    labels = rng.choice(np.array([0, 1, 2, 3, 7], np.uint8), size=(5, 6, 7), p=[0.5, 0.2, 0.1, 0.1, 0.1])
    lookup = np.array([0, 1, 1, -1, 2, 2, 2, 3], np.int32)  # labels 1 and 2 share a class; 3 is hidden
    cells = cell_classes(labels, lookup, boundary_cells(labels))
    np.testing.assert_array_equal(cells, cell_classes(labels, lookup))
    nz, ny, nx = labels.shape
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                if k == nz - 1 or j == ny - 1 or i == nx - 1:
                    assert cells[k, j, i] == MIXED
                    continue
                corners = {int(lookup[v]) for v in labels[k : k + 2, j : j + 2, i : i + 2].reshape(-1)}
                assert cells[k, j, i] == (corners.pop() if len(corners) == 1 else MIXED)
