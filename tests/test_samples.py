"""The bundled samples: they load, stay small, and are exactly what the generator makes."""

from __future__ import annotations

import json

import numpy as np
import pytest

from volren import samples
from volren.io import load_transfer_function, load_volume
from volren.model.volume import TetVolume, UniformVolume

EXPECTED = {
    "marschner_lobb": (UniformVolume, np.float32),
    "phantom_ct": (UniformVolume, np.int16),
    "hollow_cylinder": (TetVolume, np.float64),
}


@pytest.mark.parametrize("name", sorted(samples.SAMPLES))
def test_committed_samples_load_and_match_the_generator(name):
    volume_path, tf_path = samples.sample_paths(name)
    assert volume_path.parent == samples.REPO_SAMPLES
    assert volume_path.stat().st_size < 1_000_000
    volume = load_volume(volume_path)
    kind, dtype = EXPECTED[name]
    assert isinstance(volume, kind) and volume.values.dtype == dtype
    generated = samples.sample_volumes()[name]
    np.testing.assert_array_equal(volume.values, generated.values)
    if isinstance(volume, UniformVolume):
        assert volume.dimensions == generated.dimensions
        np.testing.assert_allclose(volume.spacing, generated.spacing, rtol=1e-12)
    else:
        np.testing.assert_allclose(volume.points, generated.points, rtol=0, atol=1e-12)
        np.testing.assert_array_equal(volume.tets, generated.tets)
    assert load_transfer_function(tf_path) == samples.sample_transfer_functions()[name]


def test_hollow_cylinder_is_a_valid_non_convex_mesh():
    mesh = samples.hollow_cylinder()
    from volren.model.tet_repair import signed_volumes

    volumes = signed_volumes(mesh.points, mesh.tets)
    assert np.all(volumes > 0)
    # The tets fill the annulus: pi (1 - 0.25) * 2, less the chord error of 32 facets.
    exact = np.pi * 0.75 * 2.0
    assert exact * 0.98 < volumes.sum() < exact
    radius = np.hypot(mesh.points[:, 0], mesh.points[:, 1])
    assert radius.min() == pytest.approx(0.5)  # the hole: no point inside r < 0.5


def test_installed_copies_regenerate_the_samples(tmp_path, monkeypatch):
    monkeypatch.setattr(samples, "REPO_SAMPLES", tmp_path / "absent")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    folder = samples.samples_folder()
    assert folder == tmp_path / "cache" / "volren" / "data_samples"
    volume_path, tf_path = samples.sample_paths("phantom_ct")
    assert volume_path.exists() and json.loads(tf_path.read_text())["version"] == 1


def test_the_phantoms_labels_match_the_generator_and_name_every_label():
    from volren.io.label_info import load_label_info
    from volren.io.label_io import load_labels

    labels_path, info_path = (samples.REPO_SAMPLES / f for f in samples.SAMPLE_LABELS["phantom_ct"])
    volume = load_volume(samples.sample_paths("phantom_ct")[0])
    labels = load_labels(labels_path, volume)
    generated = samples.shepp_logan_labels()
    np.testing.assert_array_equal(labels.values, generated.values)
    assert labels.present == tuple(range(11))  # the air and every ellipsoid
    info = load_label_info(info_path)
    assert info.names == generated.names and info.colors == generated.colors
    assert np.all(volume.values[labels.values == 2] < 100)  # the brain: soft tissue
    assert np.all(volume.values[labels.values == 1] > 0)  # the skull: bone
