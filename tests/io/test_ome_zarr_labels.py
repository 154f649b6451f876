"""OME-Zarr image-label groups (NGFF ``labels`` and ``image-label``) as a volume's label map: read
exactly, named and coloured from their metadata, by the label image's path, its labels group's or
the image's; several label images, another grid and non-labels refused in one line."""

from __future__ import annotations

import numpy as np
import pytest

from volren.errors import VolrenError
from volren.io import load_volume
from volren.io.label_io import load_labels

zarr = pytest.importorskip("zarr", reason="volren[zarr] is part of the test set-up")
writer = pytest.importorskip("ome_zarr.writer")
from volren.io.ome_zarr_labels import image_labels, label_hints  # noqa: E402

SHAPE = (6, 7, 8)  # z, y, x
META = {
    "colors": [{"label-value": 3, "rgba": [255, 0, 51, 128]}, {"label-value": 1, "rgba": [0, 0, 255, 255]},
               {"label-value": 2, "rgba": "red"}, {"rgba": [1, 2, 3, 4]}],
    "properties": [{"label-value": 3, "class": "liver", "area (pixels)": 18},
                   {"label-value": 1, "name": "kidney", "class": "organ"}, {"label-value": -1, "class": "bad"}],
}  # fmt: skip


def organs() -> np.ndarray:
    labels = np.zeros(SHAPE, np.uint8)
    labels[2:4, 2:5, 3:6] = 3
    labels[0, :2, :] = 1
    return labels


def image(tmp_path, names=("organs",), label_shape=SHAPE, levels: int = 1) -> tuple:
    """An image of `levels` levels (written by the ome-zarr package, NGFF 0.5) with label images `names`, each
    `organs()` (or ones of `label_shape`) with META; returns (its path, its labels)."""
    path = tmp_path / "body.zarr"
    group = zarr.open_group(str(path), mode="w")
    values = np.random.default_rng(3).random(SHAPE).astype(np.float32)
    writer.write_image(values, group, axes="zyx", scale_factors=[2**k for k in range(1, levels)])
    labels = organs()
    for name in names:
        data = labels if label_shape == SHAPE else np.ones(label_shape, np.uint8)
        writer.write_labels(
            data, group, name=name, axes="zyx", scaler=None, scale_factors=[], label_metadata=META
        )
    return path, labels


def test_a_label_image_is_read_exactly_with_its_names_and_colours(tmp_path):
    path, labels = image(tmp_path)
    volume = load_volume(path)
    assert image_labels(path) == (str(path / "labels" / "organs"),)
    for given in (path / "labels" / "organs", path / "labels", path):
        label_map = load_labels(given, volume)
        assert np.array_equal(label_map.values, labels) and label_map.name == "organs"
        assert label_map.names == {3: "liver", 1: "kidney"}  # "name" before "class"; bad entries passed over
        assert label_map.colors == {3: (1.0, 0.0, 0.2), 1: (0.0, 0.0, 1.0)}


def test_the_api_and_cli_label_path_draw_with_it(tmp_path):
    from volren.draw.labelled import labelled
    from volren.model.transfer_function import TransferFunction1D

    path, labels = image(tmp_path)
    volume = load_volume(path)
    drawn, tf = labelled(volume, TransferFunction1D.ramp(0.0, 1.0, 0.5), f"{path}/labels/organs")
    assert np.array_equal(drawn.labels.values, labels) and drawn.labels.label_name(3) == "liver"
    assert tf.style(3).color == (1.0, 0.0, 0.2)


def test_several_label_images_are_named_one_at_a_time(tmp_path):
    path, labels = image(tmp_path, ("organs", "cells"))
    volume = load_volume(path)
    for given in (path, path / "labels"):
        with pytest.raises(
            VolrenError, match=r"2 label images \(.*labels/organs, .*labels/cells\); name one"
        ):
            load_labels(given, volume)
    assert np.array_equal(load_labels(path / "labels" / "cells", volume).values, labels)


def test_labels_on_another_grid_and_fractions_are_refused_in_one_line(tmp_path):
    path, _ = image(tmp_path, label_shape=(6, 7, 9))
    volume = load_volume(path)
    with pytest.raises(
        VolrenError, match=r"organs: the label volume is 9x7x6 but body.zarr is 8x7x6"
    ) as info:
        load_labels(path / "labels" / "organs", volume)
    assert "\n" not in str(info.value)
    group = zarr.open_group(str(tmp_path / "frac.zarr"), mode="w", zarr_format=2)
    group.create_array("0", shape=SHAPE, chunks=SHAPE, dtype="float32")[:] = np.full(SHAPE, 0.5, np.float32)
    group.attrs["multiscales"] = [
        {"version": "0.4", "axes": [{"name": a} for a in "zyx"], "datasets": [{"path": "0"}]}
    ]
    group.attrs["image-label"] = META
    with pytest.raises(VolrenError, match=r"frac.zarr: labels must be whole numbers"):
        load_labels(tmp_path / "frac.zarr", volume)
    empty = zarr.open_group(str(tmp_path / "empty.zarr"), mode="w", zarr_format=2)
    empty.attrs["labels"] = []
    with pytest.raises(VolrenError, match=r"empty.zarr: an OME-Zarr labels group must list its label images"):
        load_labels(tmp_path / "empty.zarr", volume)


def test_label_hints_pass_over_malformed_entries():
    assert label_hints(None) == ({}, {})
    names, colors = label_hints({"colors": [{"label-value": 2, "rgba": [0, 255, 0]},
                                            {"label-value": True, "rgba": [1, 1, 1, 1]},
                                            {"label-value": 4, "rgba": [0, 256, 0, 1]}],
                                 "properties": "not a list"})  # fmt: skip
    assert names == {} and colors == {2: (0.0, 1.0, 0.0)}


def test_render_reads_an_ome_zarr_input_whole_for_its_label_image(tmp_path, capsys):
    from volren.cli.main import build_parser, main
    from volren.cli.render_cmd import build_scene

    path, labels = image(tmp_path, levels=2)
    argv = ["render", str(path), "--labels", f"{path}/labels/organs", "--hide-labels", "0"]
    scene, _why, source = build_scene(build_parser("render", every=False).parse_args(argv))
    assert not source.bricks and np.array_equal(scene.volume.values, load_volume(path).values)
    assert np.array_equal(scene.volume.labels.values, labels) and scene.volume.labels.names[3] == "liver"
    assert (
        scene.transfer_function.style(3).color == (1.0, 0.0, 0.2)
        and not scene.transfer_function.style(0).visible
    )
    assert main([*argv, "--level", "1", "-o", str(tmp_path / "x.png")]) == 1
    err = capsys.readouterr().err.splitlines()
    assert (
        len(err) == 1
        and "--labels: labels lie on the image's full resolution; --level 1 does not apply" in err[0]
    )


def test_the_api_reads_an_ome_zarr_image_whole_for_its_label_image(tmp_path):
    """`volren.render(image.zarr, labels=...)` draws what the image read whole draws with them."""
    import volren
    from volren.model.transfer_function import TransferFunction1D

    path, _ = image(tmp_path, levels=2)
    given = dict(labels=f"{path}/labels/organs", hidden_labels=[0], size=(24, 20), renderer="reference")
    for tf in (None, TransferFunction1D.ramp(0.0, 1.0, 0.5)):
        streamed = volren.render(str(path), tf, **given)
        whole = volren.render(load_volume(path), tf, **given)
        assert streamed[..., 3].max() > 0.01
        np.testing.assert_array_equal(streamed, whole)
    with pytest.raises(
        VolrenError, match=r"^labels: label images lie on the image's full resolution; level 1"
    ):
        volren.render(str(path), level=1, **given)
