"""UniformVolume / TetVolume: layout, dtypes, value ranges, validation; tetrahedron repair."""

from __future__ import annotations

import numpy as np
import pytest

from volren.errors import VolrenError
from volren.model import tet_repair
from volren.model.tet_repair import repair_tets, repeated_tets, signed_volumes
from volren.model.volume import TetVolume, UniformVolume


@pytest.mark.parametrize("dtype", [np.uint8, np.int16, np.uint16, np.float32, np.float64])
def test_kept_dtypes_stay_as_given(dtype):
    values = np.arange(2 * 3 * 4).reshape(2, 3, 4).astype(dtype)
    volume = UniformVolume(values, spacing=(1, 2, 3), origin=(-1, 0, 1))
    assert volume.values.dtype == dtype and not volume.notes
    assert volume.dimensions == (4, 3, 2)
    assert volume.bounds == (-1, 2, 0, 4, 1, 4)
    assert volume.value_range == (0, 23)
    assert volume.mean_spacing == 2.0


@pytest.mark.parametrize(
    "dtype, kept", [(np.int8, np.int16), (np.int32, np.float64), (np.float16, np.float32)]
)
def test_other_dtypes_are_converted_with_a_note(dtype, kept):
    volume = UniformVolume(np.ones((2, 2, 2), dtype=dtype), name="x.vti")
    assert volume.values.dtype == kept
    assert "converted" in volume.notes[0] and "x.vti" in volume.notes[0]


def test_byte_swapped_values_keep_their_type():
    big = np.arange(8, dtype=">i2").reshape(2, 2, 2)
    volume = UniformVolume(big)
    assert volume.values.dtype == np.int16 and volume.values.dtype.isnative and not volume.notes
    assert volume.values[1, 1, 1] == 7


def test_from_xyz_transposes_to_zyx():
    xyz = np.arange(24).reshape(4, 3, 2)  # [i, j, k]
    volume = UniformVolume.from_xyz(xyz)
    assert volume.dimensions == (4, 3, 2)
    assert volume.values[1, 2, 3] == xyz[3, 2, 1]


def test_nonfinite_values_are_counted_and_left_out_of_the_range():
    values = np.zeros((3, 3, 3), np.float32)
    values[0, 0, 0], values[1, 1, 1], values[2, 2, 2] = np.nan, np.inf, 5.0
    volume = UniformVolume(values, name="nan.vti")
    assert volume.nonfinite_count == 2 and volume.value_range == (0.0, 5.0)
    assert any("2 non-finite" in n for n in volume.notes)


@pytest.mark.parametrize(
    "values, kwargs, message",
    [
        (np.zeros((2, 2)), {}, "3D values"),
        (np.zeros((0, 2, 2)), {}, "empty"),
        (np.zeros((1, 5, 5)), {}, "at least 2 samples"),
        (np.full((2, 2, 2), np.nan), {}, "no finite values"),
        (np.zeros((2, 2, 2)), {"spacing": (1, 0, 1)}, "positive"),
        (np.zeros((2, 2, 2)), {"origin": (0, np.nan, 0)}, "finite"),
        (np.array([["a"]] * 2 * 2).reshape(2, 2, 1).repeat(2, 2), {}, "not numeric"),
    ],
)
def test_bad_uniform_volumes(values, kwargs, message):
    with pytest.raises(VolrenError, match=message):
        UniformVolume(values, name="bad.vti", **kwargs)


UNIT_TET = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)


def test_tet_volume_basics():
    volume = TetVolume(UNIT_TET, [[0, 1, 2, 3]], np.array([0, 1, 2, 3], np.float32))
    assert volume.bounds == (0, 1, 0, 1, 0, 1)
    assert volume.mean_edge_length == pytest.approx((3 + 3 * np.sqrt(2)) / 6)
    assert volume.values.dtype == np.float32


@pytest.mark.parametrize(
    "tets, values, message",
    [
        ([[0, 1, 2, 4]], [0, 0, 0, 0], "outside"),
        ([[0, 1, 2]], [0, 0, 0, 0], r"\(m, 4\)"),
        (np.zeros((0, 4), int), [0, 0, 0, 0], "empty"),
        ([[0, 1, 2, 3]], [0, 0, 0], "one scalar per point"),
        ([[0.0, 1, 2, 3]], [0, 0, 0, 0], "integers"),
    ],
)
def test_bad_tet_volumes(tets, values, message):
    with pytest.raises(VolrenError, match=message):
        TetVolume(UNIT_TET, np.asarray(tets), np.asarray(values, float), name="bad.vtu")


def test_repair_drops_flat_and_reorients_inverted_tets():
    points = np.vstack([UNIT_TET, [[1, 1, 0]]])
    tets = np.array([[0, 1, 2, 3], [0, 2, 1, 3], [0, 1, 2, 4], [0, 1, 1, 3]])
    result = repair_tets(points, tets)
    assert result.dropped_degenerate == 2  # coplanar points 0,1,2,4 and a repeated vertex
    assert result.reoriented == 1
    assert np.all(signed_volumes(points, result.tets) > 0)
    assert np.allclose(signed_volumes(points, result.tets), 1 / 6)


def test_repair_is_scale_invariant():
    tiny = UNIT_TET * 1e-6
    result = repair_tets(tiny, np.array([[0, 1, 2, 3]]))
    assert result.dropped_degenerate == 0


def two_tets_sharing_a_face():
    """Two cells over the unit tet's face 1-2-3, with point 0 written twice (same value)."""
    points = np.vstack([UNIT_TET, [[1, 1, 1]], UNIT_TET[:1]])
    values = np.array([0.0, 1.0, 2.0, 3.0, 4.0, 0.0])
    return points, np.array([[0, 1, 2, 3], [1, 2, 3, 4]]), values


def test_repeated_tets_match_in_any_order_after_merging_points():
    points, tets, values = two_tets_sharing_a_face()
    again = np.array([[3, 2, 1, 0], [5, 1, 2, 3], [4, 3, 2, 1], [0, 1, 2, 4]])  # last one is new
    repeated = repeated_tets(points, np.vstack([tets, again]), values)
    assert repeated.tolist() == [False, False, True, True, True, False]


def test_repeated_tets_need_the_same_value_at_a_repeated_point():
    points, tets, values = two_tets_sharing_a_face()
    values[5] = 9.0  # point 5 sits where point 0 does, with another value: a different field
    assert not repeated_tets(points, np.vstack([tets, [[5, 1, 2, 3]]]), values).any()


def test_a_hash_collision_never_merges_different_tets(monkeypatch):
    monkeypatch.setattr(tet_repair, "_mixed", lambda ids: np.zeros(len(ids), np.uint64))
    points, tets, values = two_tets_sharing_a_face()
    assert repeated_tets(points, np.vstack([tets, tets[:1]]), values).tolist() == [False, False, True]


def test_a_tet_volume_keeps_one_copy_of_each_tet_with_a_note():
    points, tets, values = two_tets_sharing_a_face()
    volume = TetVolume(points, np.vstack([tets, tets[:, ::-1], tets]), values, name="twice.vtu")
    np.testing.assert_array_equal(volume.tets, tets)
    assert volume.merged_tet_count == 4
    assert volume.notes == ("twice.vtu: 4 duplicated tetrahedra merged",)
    single = TetVolume(points, tets, values)
    assert single.merged_tet_count == 0 and not single.notes


def test_a_meshs_bounds_are_its_points_extent_computed_once():
    """The app asks for the bounds per renderer on every preview request: a mesh of a million
    points must not scan them each time (it held oxygen's TF-drag previews back until the drag ended)."""
    points = np.random.default_rng(0).normal(size=(50, 3))
    volume = TetVolume(points, [[0, 1, 2, 3]], np.zeros(50))
    lo, hi = points.min(axis=0), points.max(axis=0)
    assert volume.bounds == (lo[0], hi[0], lo[1], hi[1], lo[2], hi[2])
    assert volume.bounds is volume.bounds


def test_the_step_is_measured_in_the_smallest_spacing_so_it_holds_along_the_finest_axis():
    volume = UniformVolume(np.zeros((4, 4, 4), np.uint8), spacing=(0.5, 0.5, 5.0))
    assert volume.characteristic_length == 0.5
    assert volume.mean_spacing == 2.0


def test_a_grid_too_anisotropic_for_its_smallest_spacing_keeps_every_level_drawable():
    from volren.model.settings import MAX_SAMPLES_PER_RAY, check_step, samples_per_ray
    from volren.model.volume import FINEST_LEVEL_STEP

    slices = UniformVolume(np.zeros((4, 16, 16), np.uint8), spacing=(1.0, 1.0, 99999.0))
    unit = slices.characteristic_length
    assert unit > 1.0
    assert samples_per_ray(FINEST_LEVEL_STEP, slices.bounds, unit) == pytest.approx(MAX_SAMPLES_PER_RAY)
    check_step(0.5, slices.bounds, unit)  # the default step is drawable
