"""`volren.render` and `volren.drawing` with a label volume: labels from a file, an array or a
`LabelMap`; label info, per-label TFs and hidden labels in that order; `auto` among renderers that
draw labels; one-line errors naming the argument."""

from __future__ import annotations

import json

import numpy as np
import pytest
import pyvista as pv

import volren
from volren.errors import VolrenError, VolrenWarning
from volren.io import save_transfer_function
from volren.model.labels import PALETTE, LabelMap, LabelStyle, LabelTransferFunction
from volren.model.transfer_function import TransferFunction1D
from volren.model.transfer_function_2d import TransferFunction2D
from volren.model.volume import TetVolume, UniformVolume
from volren.quality import NOT_AUTO
from volren.renderers.registry import registry

N = 8


def ct() -> UniformVolume:
    z, y, x = np.mgrid[0:N, 0:N, 0:N]
    return UniformVolume((x + y + z).astype(np.float32), name="ct")


def halves() -> np.ndarray:
    """Label 1 where x < N/2, label 2 beyond, label 5 in one corner voxel."""
    values = np.ones((N, N, N), np.uint8)
    values[:, :, N // 2 :] = 2
    values[0, 0, 0] = 5
    return values


BASE = TransferFunction1D([[0, 1, 1, 1]], [[0, 0.0], [21, 0.6]], 4.0)


def save_labels(values: np.ndarray, path) -> None:
    img = pv.ImageData(dimensions=values.shape[::-1])
    img.point_data["labels"] = values.ravel()
    img.save(path)


@pytest.mark.parametrize("form", ["path", "array", "label map"])
def test_labels_from_a_file_an_array_or_a_label_map(tmp_path, form):
    save_labels(halves(), tmp_path / "seg.nii.gz")
    given = {"path": tmp_path / "seg.nii.gz", "array": halves(),
             "label map": LabelMap(halves(), colors={2: (0, 0, 1)})}[form]  # fmt: skip
    d = volren.drawing(ct(), BASE, renderer="reference", size=16, labels=given)
    volume, tf = d.scene.volume, d.scene.transfer_function
    assert isinstance(volume, UniformVolume) and volume.labels is not None
    np.testing.assert_array_equal(volume.labels.values, halves())
    assert isinstance(tf, LabelTransferFunction) and tf.base is BASE
    # the default look: label 0 (absent here) in the volume's TF, the others in their colour
    colors = {1: PALETTE[0], 2: (0.0, 0.0, 1.0) if form == "label map" else PALETTE[1], 5: PALETTE[2]}
    assert tf.styles == {label: LabelStyle(color=c) for label, c in colors.items()}


def test_label_info_then_label_tfs_then_hidden_labels(tmp_path):
    bone = TransferFunction1D.ramp(0, 21, 0.9)
    save_transfer_function(bone, tmp_path / "bone.json")
    own = TransferFunction1D.ramp(0, 21, 0.3)
    info = {"version": 1, "labels": {"1": {"name": "liver", "opacity": 0.5},
                                     "2": {"name": "kidney", "color": [0, 1, 0]},
                                     "5": {"tf": "bone.json"}}}  # fmt: skip
    (tmp_path / "labels.json").write_text(json.dumps(info))
    d = volren.drawing(ct(), BASE, renderer="reference", size=16, labels=halves(), label_info=tmp_path / "labels.json",
                       label_tfs={2: own, 1: str(tmp_path / "bone.json")}, hidden_labels=(5, 0))  # fmt: skip
    tf = d.scene.transfer_function
    assert d.scene.volume.labels.names == {1: "liver", 2: "kidney"}
    assert d.scene.volume.labels.colors == {2: (0.0, 1.0, 0.0)}
    assert tf.styles == {
        1: LabelStyle(opacity=0.5, tf=bone),  # the info's opacity kept; a TF of its own, in its own colours
        2: LabelStyle(color=(0.0, 1.0, 0.0), tf=own),  # the info's colour kept over its TF
        5: LabelStyle(visible=False, tf=bone),
        0: LabelStyle(visible=False),
    }


def test_a_volume_with_labels_and_a_tf_per_label_draws_as_given():
    volume = UniformVolume(ct().values, labels=LabelMap(halves()))
    tf = LabelTransferFunction(BASE, {2: LabelStyle(visible=False)})
    d = volren.drawing(volume, tf, renderer="reference", size=16)
    assert d.scene.volume is volume
    assert d.scene.transfer_function.to_dict() == tf.to_dict()
    # and with hidden labels on top, the TF given is left as it was
    d = volren.drawing(volume, tf, renderer="reference", size=16, hidden_labels=[1])
    assert set(d.scene.transfer_function.styles) == {1, 2} and set(tf.styles) == {2}


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"labels": np.ones((N, N, N - 1), np.uint8)}, "labels: the label volume is 7x8x8 but ct is 8x8x8"),
    ({"labels": np.full((N, N, N), 0.5)}, "labels: labels must be whole numbers"),
    ({"label_tfs": {3: BASE}}, "label_tfs needs a label volume: give labels"),
    ({"hidden_labels": (0,)}, "hidden_labels needs a label volume: give labels"),
    ({"labels": halves(), "hidden_labels": "0,7"}, "hidden_labels: give the labels as a list of whole numbers"),
    ({"labels": halves(), "hidden_labels": 7}, "hidden_labels: give the labels as a list of whole numbers, got 7"),
    ({"labels": halves(), "hidden_labels": (-1,)}, "hidden_labels: a label is a whole number in 0..65535, got -1"),
    ({"labels": halves(), "label_tfs": {"x": BASE}}, "label_tfs: a label is a whole number in 0..65535, got 'x'"),
    ({"labels": halves(), "label_tfs": {1: TransferFunction2D((0, 1), (0, 1))}},
     "label_tfs: label 1: a label's transfer function is 1D, got a 2D TF"),
    ({"labels": halves(), "label_tfs": {1: "nowhere.json"}}, "label_tfs: nowhere.json: no such file"),
    ({"labels": halves(), "label_info": 3}, "label_info: give a label-info JSON file or dict, got a int"),
    ({"labels": "nowhere.nii.gz"}, "labels: nowhere.nii.gz: no such file or folder"),
    ({"labels": halves(), "tf": TransferFunction2D((0, 21), (0, 1))},
     "labels: labels draw with a 1D transfer function per label; got a 2D one"),
])  # fmt: skip
def test_bad_label_arguments_are_one_line_naming_the_argument(kwargs, message):
    kwargs = {"tf": BASE, **kwargs}
    with pytest.raises(VolrenError) as exc:
        volren.drawing(ct(), renderer="reference", size=16, **kwargs)
    assert str(exc.value).startswith(message)


def test_labels_on_a_mesh_are_refused():
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float64)
    mesh = TetVolume(points, np.array([[0, 1, 2, 3]]), np.arange(4.0), name="mesh")
    with pytest.raises(
        VolrenError, match=r"^labels: label volumes are for uniform grids; mesh is a tetrahedral mesh"
    ):
        volren.drawing(mesh, renderer="reference", size=16, labels=np.zeros((2, 2, 2), np.uint8))


def test_a_tf_per_label_that_shows_nothing_is_warned():
    """`check_scene` looks at the TFs of the labels that occur: a warning only where none shows."""
    zero = TransferFunction1D([[0, 1, 1, 1]], [[0, 0.0], [21, 0.0]])
    with pytest.warns(VolrenWarning, match=r"no label shows anything; label 1: the opacity is 0 over"):
        volren.drawing(ct(), zero, renderer="reference", size=16, labels=halves())
    volren.drawing(
        ct(), zero, renderer="reference", size=16, labels=halves(), label_tfs={5: BASE}
    )  # no warning


def _draws_labels(name: str) -> bool:
    support = registry.capabilities(name).kinds.get("uniform")
    return bool(support is not None and support.labels)


def test_auto_picks_a_renderer_that_draws_labels():
    labelled = [n for n in registry.names() if n not in NOT_AUTO and _draws_labels(n)]
    if not labelled:
        with pytest.raises(
            VolrenError, match=r"^no registered renderer can draw this uniform scene with labels"
        ):
            volren.drawing(ct(), BASE, size=16, labels=halves())
        return
    d = volren.drawing(ct(), BASE, size=16, labels=halves())
    assert d.scene.renderer in labelled
    support = registry.capabilities(d.scene.renderer).kinds["uniform"]
    assert not d.scene.settings.preintegration or support.labels_preintegration


def test_the_reference_draws_labels_as_their_tfs_say():
    """Exact oracles through `volren.render`: every label drawn with the volume's TF is the volume
    drawn without labels (the weights of a voxel's labels sum to 1: RTVG 16.5), and every label
    hidden is black. Until the reference draws labels, its refusal is what comes back."""
    kwargs = {"renderer": "reference", "size": 16, "azimuth": 30, "elevation": 20}
    if not _draws_labels("reference"):
        with pytest.raises(VolrenError, match=r"renderer reference does not draw label volumes"):
            volren.render(ct(), BASE, labels=halves(), **kwargs)
        return
    plain = volren.render(ct(), BASE, **kwargs)
    assert plain.max() > 0.05
    same = volren.render(ct(), BASE, labels=halves(), label_tfs={1: BASE, 2: BASE, 5: BASE}, **kwargs)
    np.testing.assert_allclose(same, plain, atol=1e-5)  # float32 images; the label path classifies per label
    with pytest.warns(
        VolrenWarning, match="every label in the label volume is hidden, so the image is black"
    ):
        hidden = volren.render(ct(), BASE, labels=halves(), hidden_labels=(1, 2, 5), **kwargs)
    assert not hidden.any()
