"""The TF classes (`volren.model.tf_class`) and scene classes (`volren.model.scene_class`) that
quality levels are chosen by."""

from types import SimpleNamespace

import numpy as np
import pytest

from volren.model.scene_class import SceneClass
from volren.model.tf_class import BAND_TF, SHARP_TF, TFClass, tf_sharpness, tf_visible_fraction

UNIFORM, TET = SceneClass("uniform"), SceneClass("tet")
SHARP, BAND = SceneClass("uniform", TFClass.SHARP), SceneClass("uniform", TFClass.BAND)


def test_tf_sharpness_is_the_steepest_optical_depth_change_across_the_data_range():
    from volren.model import TransferFunction1D

    ramp = TransferFunction1D([[0, 1, 1, 1], [10, 1, 1, 1]], [[0, 0.0], [10, 0.5]])
    # -ln(1 - a) rises by ln 2 over the TF's whole span; over data spanning half of it, half that
    assert tf_sharpness(ramp, (0.0, 10.0)) == pytest.approx(np.log(2.0))
    assert tf_sharpness(ramp, (0.0, 5.0)) == pytest.approx(np.log(2.0) / 2)
    assert TFClass.of(ramp, (0.0, 10.0)) == TFClass.SMOOTH
    # the same rise over a hundredth of the data's range is sharp
    assert tf_sharpness(ramp, (0.0, 1000.0)) == pytest.approx(100 * np.log(2.0))
    assert TFClass.of(ramp, (0.0, 1000.0)) == TFClass.SHARP
    step = TransferFunction1D([[0, 1, 1, 1], [10, 1, 1, 1]], [[0, 0.0], [5, 0.0], [5, 0.2], [10, 0.2]])
    assert tf_sharpness(step, (0.0, 10.0)) == np.inf and TFClass.of(step, (0.0, 10.0)) == TFClass.SHARP
    flat = TransferFunction1D([[0, 1, 1, 1], [10, 1, 1, 1]], [[0, 0.3], [10, 0.3]])
    assert tf_sharpness(flat, (0.0, 10.0)) == 0.0
    assert tf_sharpness(ramp, (3.0, 3.0)) == 0.0  # constant data: nothing to be sharp over
    assert TFClass.of(object(), (0.0, 1.0)) is None  # not a 1D TF (a 2D one): no class
    assert tf_visible_fraction(object(), (0.0, 1.0)) is None
    assert SceneClass.of(SimpleNamespace(kind="uniform", value_range=(0.0, 1000.0)), ramp) == SHARP
    assert SceneClass.of(SimpleNamespace(kind="tet", value_range=(0.0, 1.0)), object()) == TET
    assert SceneClass.parse("uniform/sharp").volume == UNIFORM and SceneClass.parse(str(SHARP)) == SHARP


def test_a_sharp_tf_visible_on_a_narrow_part_of_the_range_is_a_band_tf():
    from volren.model import TransferFunction1D

    grey = [[0, 1, 1, 1], [100, 1, 1, 1]]
    # a peak 4 wide (visible on (48, 52)) and a step up to a solid body (visible on (40, 100])
    peak = TransferFunction1D(grey, [[0, 0.0], [48, 0.0], [50, 0.9], [52, 0.0], [100, 0.0]])
    step = TransferFunction1D(grey, [[0, 0.0], [40, 0.0], [42, 0.9], [100, 0.9]])
    assert tf_visible_fraction(peak, (0.0, 100.0)) == pytest.approx(0.04, abs=1e-3)
    assert tf_visible_fraction(step, (0.0, 100.0)) == pytest.approx(0.6, abs=1e-3)
    assert tf_sharpness(peak, (0.0, 100.0)) > SHARP_TF
    assert TFClass.of(peak, (0.0, 100.0)) == TFClass.BAND and TFClass.of(step, (0.0, 100.0)) == TFClass.SHARP
    # a gentle hump visible on a narrow part of a wide range stays smooth (band TFs are sharp ones)
    hump = TransferFunction1D(grey, [[0, 0.0], [45, 0.0], [50, 0.002], [55, 0.0], [100, 0.0]])
    assert TFClass.of(hump, (0.0, 100.0)) == TFClass.SMOOTH
    assert TFClass.of_features(SHARP_TF, BAND_TF) == TFClass.SHARP
    assert SceneClass.of(SimpleNamespace(kind="uniform", value_range=(0.0, 100.0)), peak) == BAND


def test_a_tfs_class_is_kept_until_its_opacity_points_change(monkeypatch):
    from volren.model import TransferFunction1D, tf_class

    grey = [[0, 1, 1, 1], [100, 1, 1, 1]]
    monkeypatch.setattr(tf_class, "_classes", {})  # none kept from other tests
    tf = TransferFunction1D(grey, [[0, 0.0], [100, 0.5]])
    assert TFClass.of(tf, (0.0, 100.0)) == TFClass.SMOOTH
    computed = []
    monkeypatch.setattr(tf_class, "tf_sharpness", lambda *a: computed.append(a) or tf_sharpness(*a))
    assert TFClass.of(tf, (0.0, 100.0)) == TFClass.SMOOTH and computed == []  # kept
    tf.set_opacity_points([[0, 0.0], [48, 0.0], [50, 0.9], [52, 0.0], [100, 0.0]])  # the same TF, edited
    assert TFClass.of(tf, (0.0, 100.0)) == TFClass.BAND and len(computed) == 1
    assert TFClass.of(tf, (0.0, 10000.0)) == TFClass.BAND and len(computed) == 2  # another value range
